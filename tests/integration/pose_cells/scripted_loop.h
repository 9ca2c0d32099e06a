#pragma once
// A scripted drive for pose-cell and experience-map tests: laps of a square (4 sides of 25
// frames at 4 m/s, 10 Hz, a 90-degree left turn in each side's last frame). The first lap learns
// a new view template every second frame; later laps see the same templates at the same places,
// so the first view of lap 2 closes the loop. Odometry is exact, so every run of the same
// frames gives the same actions.

#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "rslam/msg/all_messages.h"
#include "services/templates/view_match_message.h"

namespace rslam::testing {

struct ScriptedFrame {
  msg::Velocity velocity;
  msg::ViewTemplate view;
};

// The frame's view as the pose-cell service hands it to the network.
inline templates::ViewMatch MatchOf(const ScriptedFrame& f) { return templates::FromViewMessage(f.view); }

inline constexpr int kLapFrames = 100;
inline constexpr int kSideFrames = 25;
inline constexpr int kFramesPerTemplate = 2;
inline constexpr int kTemplatesPerLap = kLapFrames / kFramesPerTemplate;

inline msg::Header ScriptedHeader(uint64_t frame, const std::string& robot = "robot1") {
  return {robot, frame, 1'000'000'000 + static_cast<int64_t>(frame) * 100'000'000};
}

inline ScriptedFrame ScriptedLoopFrame(uint64_t i, const std::string& robot = "robot1") {
  ScriptedFrame f;
  f.velocity.header = ScriptedHeader(i, robot);
  f.velocity.dt_s = i == 0 ? 0.0 : 0.1;
  f.velocity.vtrans_mps = i == 0 ? 0.0 : 4.0;
  f.velocity.vrot_radps = (i % kSideFrames == kSideFrames - 1) ? (std::numbers::pi / 2) / 0.1 : 0.0;
  f.velocity.source = msg::VelocitySource::VELOCITY_VISUAL;
  f.view.header = f.velocity.header;
  const uint64_t lap_frame = i % kLapFrames;
  f.view.template_id = static_cast<uint32_t>(lap_frame / kFramesPerTemplate);
  f.view.is_new = i < kLapFrames && lap_frame % kFramesPerTemplate == 0;
  f.view.relative_angle_rad = 0.0;
  f.view.difference = f.view.is_new ? 0.2 : 0.01;
  f.view.template_count =
      i < kLapFrames ? static_cast<uint32_t>(lap_frame / kFramesPerTemplate + 1) : static_cast<uint32_t>(kTemplatesPerLap);
  return f;
}

inline std::vector<ScriptedFrame> ScriptedLoop(int frames, const std::string& robot = "robot1") {
  std::vector<ScriptedFrame> out;
  for (int i = 0; i < frames; ++i) out.push_back(ScriptedLoopFrame(static_cast<uint64_t>(i), robot));
  return out;
}

}  // namespace rslam::testing
