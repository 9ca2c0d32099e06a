#include "tools/run/run_statistics.h"

namespace rslam::run {

void RunStatistics::Add(const FrameRecord& record, uint32_t template_count) {
  curve_.push_back(TemplateCurvePoint{record.frame_index, record.stamp_ns, record.view.template_id, record.view.is_new,
                                      template_count});
  total_.odometry += record.micros.odometry;
  total_.templates += record.micros.templates;
  total_.pose_cells += record.micros.pose_cells;
  total_.experience_map += record.micros.experience_map;
}

StageMicroseconds RunStatistics::MeanMilliseconds() const {
  StageMicroseconds mean;
  if (curve_.empty()) return mean;
  const double scale = 1e-3 / static_cast<double>(curve_.size());
  mean.odometry = total_.odometry * scale;
  mean.templates = total_.templates * scale;
  mean.pose_cells = total_.pose_cells * scale;
  mean.experience_map = total_.experience_map * scale;
  return mean;
}

double RunStatistics::CoreFramesPerSecond() const {
  const double total = total_.total();
  return total > 0 ? static_cast<double>(curve_.size()) / (total * 1e-6) : 0.0;
}

}  // namespace rslam::run
