#pragma once
// The one QoS table. Every topic uses one of these presets; both vendors get every field set
// explicitly (their defaults differ: Fast DDS writers default to transient-local, Cyclone to
// volatile), so a Cyclone endpoint and a Fast DDS endpoint with the same preset always match.

#include <cstdint>
#include <string_view>

namespace rslam::bus {

enum class QosPreset {
  // Camera images: reliable, keep-last 8, volatile. A slow reader loses old frames rather
  // than stalling the camera. (Acknowledgment is not consumption: a keep-last reader acks a
  // sample when it reaches its cache, so a camera that must lose nothing paces itself on its
  // readers' outputs instead: rslam-camera's lockstep mode.)
  kSensor,
  // Odometry, views, actions, commands: reliable, keep-all, volatile. Nothing is lost; a slow
  // reader applies back-pressure (the writer blocks up to max_blocking_ms).
  kStream,
  // A replayable log (pose-cell actions): reliable, keep-last 200,000 (hours of frames),
  // transient-local, so a consumer that restarts receives every entry it missed.
  kLog,
  // Maps, grids, status: reliable, transient-local, keep-last 1 per instance (robot), so a
  // service that (re)starts gets the latest at once.
  kState,
};

struct QosSettings {
  bool reliable;
  bool keep_all;
  int32_t depth;            // keep-last depth (ignored for keep-all)
  bool transient_local;
  int32_t max_blocking_ms;  // how long a reliable writer may block on a full reader
};

inline constexpr QosPreset kAllQosPresets[] = {QosPreset::kSensor, QosPreset::kStream, QosPreset::kLog,
                                               QosPreset::kState};

QosSettings SettingsOf(QosPreset preset);
std::string_view PresetName(QosPreset preset);
// The preset named by PresetName; throws std::invalid_argument naming the known ones.
QosPreset ParseQosPreset(std::string_view name);

}  // namespace rslam::bus
