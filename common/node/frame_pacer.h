#pragma once
// Lockstep pacing of a frame source (the simulator, or the camera service on a recorded source
// with rate_hz 0): frame N may be published once every live downstream stage has reported frame
// >= N - max_frames_in_flight, so the source never runs ahead of the pipeline (no dropped frames,
// the same map at any machine speed) and never waits for a stage that is not there:
//   - a stage that has reported is live while its last report is younger than stage_timeout;
//   - a stage that has never reported is waited for until startup_timeout after the first frame.
// Each per-frame service (odometry, templates, ...) publishes one output per frame with the
// frame's seq; those are the reports. DDS acknowledgments would not do: a reliable keep-last reader
// acknowledges a sample when it reaches the reader's cache, not when the application takes it.
// Pure logic: the caller passes the (steady) clock readings.

#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

namespace rslam {

class FramePacer {
 public:
  using Clock = std::chrono::steady_clock;

  // Throws std::invalid_argument on max_frames_in_flight < 1 or a negative timeout.
  FramePacer(int stage_count, int max_frames_in_flight, Clock::duration stage_timeout,
             Clock::duration startup_timeout);

  // The first frame goes out now: the startup timeout counts from here.
  void Start(Clock::time_point now);
  // A stage reported it finished frame_seq. Throws std::out_of_range on a bad stage index.
  void Report(int stage, uint64_t frame_seq, Clock::time_point now);
  // Whether frame_seq may be published now.
  bool MayPublish(uint64_t frame_seq, Clock::time_point now) const;
  // Whether frame_seq may go only because a stage that is behind is silent or never came up:
  // the caller then paces itself (real time), so a missing stage does not make it run flat out.
  bool PassingAbsentStage(uint64_t frame_seq, Clock::time_point now) const;
  // The latest frame a stage reported, if any.
  std::optional<uint64_t> LastReported(int stage) const;

  int stage_count() const { return static_cast<int>(stages_.size()); }

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

}  // namespace rslam
