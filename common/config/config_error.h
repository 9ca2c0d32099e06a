#pragma once
// The one error type for bad configuration: it always names the offending key.

#include <stdexcept>
#include <string>
#include <string_view>

namespace rslam {

class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string key, std::string reason)
      : std::runtime_error(key + ": " + reason), key_(std::move(key)), reason_(std::move(reason)) {}
  const std::string& key() const { return key_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string key_;
  std::string reason_;
};

// Throws ConfigError(key, reason) unless ok. Used by every config struct's Validate().
inline void Require(bool ok, std::string_view key, std::string_view reason) {
  if (!ok) throw ConfigError(std::string(key), std::string(reason));
}

// Validates a nested section; its errors name the key as "prefix.key".
template <class T>
void ValidateNested(const T& section, const std::string& prefix) {
  try {
    section.Validate();
  } catch (const ConfigError& e) {
    throw ConfigError(prefix + "." + e.key(), e.reason());
  }
}

}  // namespace rslam
