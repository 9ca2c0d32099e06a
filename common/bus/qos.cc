#include "common/bus/qos.h"

#include <stdexcept>
#include <string>

namespace rslam::bus {

QosSettings SettingsOf(QosPreset preset) {
  switch (preset) {
    case QosPreset::kSensor:
      return {.reliable = true, .keep_all = false, .depth = 8, .transient_local = false, .max_blocking_ms = 100};
    case QosPreset::kStream:
      return {.reliable = true, .keep_all = true, .depth = 1, .transient_local = false, .max_blocking_ms = 10000};
    case QosPreset::kLog:
      return {.reliable = true, .keep_all = false, .depth = 200'000, .transient_local = true, .max_blocking_ms = 10000};
    case QosPreset::kState:
      return {.reliable = true, .keep_all = false, .depth = 1, .transient_local = true, .max_blocking_ms = 1000};
  }
  return {};
}

std::string_view PresetName(QosPreset preset) {
  switch (preset) {
    case QosPreset::kSensor: return "sensor";
    case QosPreset::kStream: return "stream";
    case QosPreset::kLog: return "log";
    case QosPreset::kState: return "state";
  }
  return "?";
}

QosPreset ParseQosPreset(std::string_view name) {
  std::string known;
  for (QosPreset preset : kAllQosPresets) {
    if (PresetName(preset) == name) return preset;
    known += (known.empty() ? "" : ", ") + std::string(PresetName(preset));
  }
  throw std::invalid_argument("unknown QoS preset '" + std::string(name) + "' (" + known + ")");
}

}  // namespace rslam::bus
