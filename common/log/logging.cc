#include "common/log/logging.h"

#include <spdlog/sinks/stdout_color_sinks.h>

#include "common/config/config_error.h"

namespace rslam {

void SetupLogging(const std::string& process_name, const std::string& level) {
  const auto parsed = spdlog::level::from_str(level);
  // from_str maps anything unknown to "off"; only "off" itself may mean off.
  Require(parsed != spdlog::level::off || level == "off", "log_level",
          "unknown level '" + level + "' (trace, debug, info, warn, error, off)");
  auto logger = spdlog::stderr_color_mt(process_name);
  logger->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  logger->set_level(parsed);
  spdlog::set_default_logger(logger);
}

}  // namespace rslam
