#pragma once
// Progress of `rslam run` on stderr: a bar redrawn in place on a terminal, plain lines every few
// seconds otherwise (logs, CI), nothing when quiet.

#include <chrono>
#include <cstdint>
#include <ostream>

namespace rslam::run {

class ProgressReporter {
 public:
  enum class Style { kBar, kLines, kQuiet };

  // total_frames: -1 when unknown. Bar redraws at most every 0.1 s, lines every 5 s.
  ProgressReporter(std::ostream& out, Style style, int64_t total_frames);

  void Update(uint64_t frames, uint64_t templates, uint64_t experiences);
  // The final state, and a newline after the bar.
  void Finish(uint64_t frames, uint64_t templates, uint64_t experiences);

 private:
  using Clock = std::chrono::steady_clock;
  void Print(uint64_t frames, uint64_t templates, uint64_t experiences);

  std::ostream& out_;
  const Style style_;
  const int64_t total_;
  const Clock::time_point start_;
  Clock::time_point last_print_;
  bool printed_ = false;
};

}  // namespace rslam::run
