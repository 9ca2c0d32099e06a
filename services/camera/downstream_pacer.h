#pragma once
// Lockstep pacing of a recorded source (rate_hz 0) by what the pipeline has finished.
//
// Waiting for DDS acknowledgments is not enough for "lose nothing": a reliable keep-last reader
// acknowledges a sample when it reaches the reader's cache, not when the application takes it,
// so a reader that falls more than the preset's depth (8) behind loses the oldest frames. Each
// per-frame service (odometry, templates, ...) publishes one output per frame with the frame's
// seq, so the camera can wait for those instead:
//   frame N may go out once every live stage reported a frame >= N - max_frames_in_flight;
//   a stage that reported before is live while its last report is younger than stage_timeout;
//   a stage that never reported is waited for until startup_timeout after the first frame
//   (a stage that is not running never blocks the camera for long).
// Pure logic: the caller passes the steady-clock readings.

#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

namespace rslam::camera {

class DownstreamPacer {
 public:
  using Clock = std::chrono::steady_clock;

  // Throws std::invalid_argument for max_frames_in_flight < 0 or negative timeouts.
  DownstreamPacer(int stage_count, int max_frames_in_flight, Clock::duration stage_timeout,
                  Clock::duration startup_timeout);

  // The first frame went out at `now`.
  void Start(Clock::time_point now);
  // Stage `stage` finished frame_seq. Throws std::out_of_range for a bad stage.
  void Report(int stage, uint64_t frame_seq, Clock::time_point now);
  // Whether frame_seq may be published at `now`.
  bool MayPublish(uint64_t frame_seq, Clock::time_point now) const;

 private:
  struct Stage {
    std::optional<uint64_t> last_seq;
    Clock::time_point last_report{};
  };
  const int max_frames_in_flight_;
  const Clock::duration stage_timeout_;
  const Clock::duration startup_timeout_;
  std::optional<Clock::time_point> started_;
  std::vector<Stage> stages_;
};

}  // namespace rslam::camera
