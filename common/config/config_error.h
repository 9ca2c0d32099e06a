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

}  // namespace rslam
