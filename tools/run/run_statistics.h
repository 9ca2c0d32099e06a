#pragma once
// What a run of the RatSLAM core did, frame by frame: the template-count curve (paper 000 fig. 9a)
// and the time spent in each stage.

#include <cstdint>
#include <vector>

#include "tools/run/ratslam_runner.h"

namespace rslam::run {

struct TemplateCurvePoint {
  uint64_t frame = 0;
  int64_t stamp_ns = 0;
  uint32_t template_id = 0;
  bool is_new = false;
  uint32_t template_count = 0;  // templates stored after this frame
};

class RunStatistics {
 public:
  // Adds one processed frame; template_count is the library size after it.
  void Add(const FrameRecord& record, uint32_t template_count);

  uint64_t frames() const { return curve_.size(); }
  const std::vector<TemplateCurvePoint>& template_curve() const { return curve_; }
  // Totals over all frames, microseconds.
  const StageMicroseconds& total_micros() const { return total_; }
  // Mean milliseconds per frame of each stage (0 without frames).
  StageMicroseconds MeanMilliseconds() const;
  // Frames per second of the four stages alone (no decoding, no output): frames / total time.
  double CoreFramesPerSecond() const;

 private:
  std::vector<TemplateCurvePoint> curve_;
  StageMicroseconds total_;
};

}  // namespace rslam::run
