#pragma once
// The one logger setup: every process calls SetupLogging once in main. Libraries never log.

#include <spdlog/spdlog.h>

#include <string>

namespace rslam {

// Logs to stderr as "[time] [name] [level] message". level: trace, debug, info, warn, error, off.
// An unknown level is a ConfigError naming "log_level".
void SetupLogging(const std::string& process_name, const std::string& level = "info");

}  // namespace rslam
