#pragma once
// The one config loader. A config struct lists its fields once, with defaults beside them:
//
//   struct FooConfig {
//     double gain = 1.0;
//     template <class V> void VisitFields(V& v) { v("gain", gain, "multiplies the input"); }
//     void Validate() const { Require(gain > 0, "gain", "must be positive"); }
//   };
//
// and the same list fills it from YAML (unknown keys and wrong types are errors naming the full
// key, e.g. "pose_cells.dim_xy"), validates it, and prints it for --help.
// Field types: bool, int, int64_t, uint32_t, double, std::string, std::vector of those, and
// nested structs that have VisitFields.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "common/config/config_error.h"

namespace rslam {

namespace config_detail {

struct NullVisitor {
  template <class F>
  void operator()(const char*, F&, const char*) {}
};

template <class T>
concept HasFields = requires(T& t, NullVisitor& v) { t.VisitFields(v); };

template <class T>
concept HasValidate = requires(const T& t) { t.Validate(); };

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

template <class T>
const char* TypeName() {
  if constexpr (std::is_same_v<T, bool>) return "true or false";
  else if constexpr (std::is_integral_v<T>) return "an integer";
  else if constexpr (std::is_floating_point_v<T>) return "a number";
  else if constexpr (std::is_same_v<T, std::string>) return "a string";
  else return "a value";
}

template <class T>
void Decode(const YAML::Node& node, const std::string& key, T& out);

template <class T>
void DecodeMap(const YAML::Node& node, const std::string& prefix, T& cfg);

struct YamlReader {
  const YAML::Node& node;
  std::string prefix;
  std::set<std::string> known;

  template <class F>
  void operator()(const char* key, F& field, const char* /*help*/) {
    known.insert(key);
    const YAML::Node child = node[key];
    if (child) Decode(child, prefix + key, field);
  }
};

template <class T>
void Decode(const YAML::Node& node, const std::string& key, T& out) {
  if constexpr (HasFields<T>) {
    DecodeMap(node, key + ".", out);
  } else if constexpr (IsVector<T>::value) {
    if (!node.IsSequence()) throw ConfigError(key, "expected a list");
    T values;
    for (std::size_t i = 0; i < node.size(); ++i) {
      typename T::value_type v{};
      Decode(node[i], key + "[" + std::to_string(i) + "]", v);
      values.push_back(std::move(v));
    }
    out = std::move(values);
  } else {
    if (!node.IsScalar()) throw ConfigError(key, std::string("expected ") + TypeName<T>());
    try {
      out = node.as<T>();
    } catch (const YAML::Exception&) {
      throw ConfigError(key, std::string("expected ") + TypeName<T>() + ", got '" + node.Scalar() + "'");
    }
  }
}

template <class T>
void DecodeMap(const YAML::Node& node, const std::string& prefix, T& cfg) {
  const std::string here = prefix.empty() ? std::string("<top level>") : prefix.substr(0, prefix.size() - 1);
  if (node.IsNull()) return;
  if (!node.IsMap()) throw ConfigError(here, "expected a mapping of keys");
  YamlReader reader{node, prefix, {}};
  cfg.VisitFields(reader);
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (!reader.known.count(key)) throw ConfigError(prefix + key, "unknown key");
  }
}

struct HelpWriter {
  std::ostream& os;
  std::string prefix;

  template <class F>
  void operator()(const char* key, F& field, const char* help) {
    if constexpr (HasFields<F>) {
      HelpWriter nested{os, prefix + key + "."};
      field.VisitFields(nested);
    } else {
      os << "  " << prefix << key << " = ";
      if constexpr (IsVector<F>::value) {
        os << "[";
        for (std::size_t i = 0; i < field.size(); ++i) os << (i ? ", " : "") << field[i];
        os << "]";
      } else if constexpr (std::is_same_v<F, bool>) {
        os << (field ? "true" : "false");
      } else {
        os << field;
      }
      os << "\n      " << help << "\n";
    }
  }
};

}  // namespace config_detail

// Validates cfg, prefixing the key of any error with `section.`.
template <class T>
void ValidateConfig(const T& cfg, std::string_view section) {
  if constexpr (config_detail::HasValidate<T>) {
    try {
      cfg.Validate();
    } catch (const ConfigError& e) {
      throw ConfigError(section.empty() ? e.key() : std::string(section) + "." + e.key(), e.reason());
    }
  }
}

// Fills cfg from root[section] (or root itself when section is empty) over its defaults, then
// validates. An absent section keeps the defaults.
template <class T>
void LoadConfigSection(const YAML::Node& root, std::string_view section, T& cfg) {
  if (section.empty()) {
    config_detail::DecodeMap(root, "", cfg);
  } else if (root.IsMap() && root[std::string(section)]) {
    config_detail::DecodeMap(root[std::string(section)], std::string(section) + ".", cfg);
  }
  ValidateConfig(cfg, section);
}

// Reads a YAML file; a missing or malformed file is a ConfigError naming the file.
YAML::Node LoadYamlFile(const std::string& path);

// Applies "a.b.c=value" overrides (from --set) onto a YAML tree.
void ApplyOverride(YAML::Node& root, const std::string& assignment);

// Every field of cfg with its current value and help text, one per line, for --help.
template <class T>
std::string DescribeConfig(T& cfg, std::string_view section = {}) {
  std::ostringstream os;
  config_detail::HelpWriter writer{os, section.empty() ? std::string() : std::string(section) + "."};
  cfg.VisitFields(writer);
  return os.str();
}

}  // namespace rslam
