#pragma once
// The Radial Obstacle Profile (ROP) of paper 003 (section 1, Fig. 2; Taylor et al. 2004): for each
// bearing bin, the range from the robot to the nearest obstacle on a flat floor, found by scanning
// the floor mask outwards from the robot along that bearing (upwards in the image) until the first
// non-floor pixel; the range is halfway between that sample and the last floor one. Bearings
// where the floor is seen all the way to the scan range are "free to range"; bearings whose
// nearest visible floor pixel is already not floor are "blind": the obstacle's base lies in the
// blind area in front of the robot (section 3.1).
//
// RopExtractor precomputes, per bearing bin, the pixels that the floor points at range steps
// along that bearing fall on (the inverse perspective lookup turned around), so a profile costs one
// mask read per sample. PirouetteProfileBuilder merges the views of a pirouette (12 x 30 degrees
// in the paper) into a 360-degree profile, averaging the overlapping views.
// A view that saw free floor only up to a shorter range than an obstacle (its ray left the image
// first) does not contradict the obstacle, so only free views reaching past it vote against it.

#include <Eigen/Core>

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "common/config/config_error.h"
#include "services/occupancy/inverse_perspective_map.h"

namespace rslam::occupancy {

enum class BinStatus : uint8_t {
  kUnobserved = 0,  // no view covered this bearing
  kObstacle = 1,    // range_m = distance to the nearest obstacle
  kFree = 2,        // no obstacle up to range_m (the scan limit or the image edge)
  kBlind = 3,       // obstacle fills the view: something lies closer than nearest_visible_m
};

struct RopBin {
  float range_m = 0.0f;
  float nearest_visible_m = 0.0f;  // where the visible floor starts on this bearing
  BinStatus status = BinStatus::kUnobserved;
};

// Bin i covers bearings [first_bearing_rad + i * bin_width_rad, + bin_width_rad), centre at
// + (i + 0.5) * bin_width_rad. Bearings are in the robot frame, counter-clockwise from forward.
struct RadialObstacleProfile {
  double first_bearing_rad = 0.0;
  double bin_width_rad = 0.0;
  std::vector<RopBin> bins;
  double BinCentre(size_t i) const { return first_bearing_rad + (i + 0.5) * bin_width_rad; }
  // The obstacle bins' points (the range along the bin's centre bearing) in the robot frame, in
  // bearing order: the floor boundary. `out` is cleared first.
  void ObstaclePoints(std::vector<Eigen::Vector2d>& out) const;
};

struct RopConfig {
  double bin_width_deg = 1.0;
  double scan_range_m = 0.60;  // how far along each bearing the mask is read
  double range_step_m = 0.005;

  template <class V>
  void VisitFields(V& v) {
    v("bin_width_deg", bin_width_deg, "bearing bin width (degrees)");
    v("scan_range_m", scan_range_m, "how far along each bearing the floor mask is scanned (m)");
    v("range_step_m", range_step_m, "range step of the scan (m)");
  }
  void Validate() const;
};

class RopExtractor {
 public:
  RopExtractor(RopConfig config, const InversePerspectiveMap& ipm);
  RopExtractor(const RopExtractor&) = delete;
  RopExtractor& operator=(const RopExtractor&) = delete;

  // floor_mask: CV_8U of the camera's size, non-zero = floor. Throws std::invalid_argument else.
  RadialObstacleProfile Extract(const cv::Mat& floor_mask) const;

  size_t bin_count() const { return rays_.size(); }

 private:
  struct Ray {
    std::vector<int32_t> pixel_index;  // row-major index of each visible sample, nearest first
    std::vector<float> range_m;
  };
  const RopConfig config_;
  const int width_, height_;
  double first_bearing_rad_ = 0.0;
  std::vector<Ray> rays_;
};

// Merges the profiles of one pirouette into a profile of 360 / bin_width_deg bins starting at -pi.
// heading_rad of each view is relative to the pirouette's reference heading (usually the pose the
// profile will be anchored at). Overlapping views vote: obstacle against free; obstacle ranges
// are averaged (the paper's reason for 30-degree steps with a 60-degree lens).
class PirouetteProfileBuilder {
 public:
  explicit PirouetteProfileBuilder(double bin_width_deg = 1.0);
  void AddView(const RadialObstacleProfile& view, double heading_rad);
  RadialObstacleProfile Build() const;
  void Clear();
  int view_count() const { return view_count_; }

 private:
  struct Accumulator {
    std::vector<float> obstacle_ranges;
    std::vector<float> free_ranges;
    int blind = 0;
    float nearest_visible = 0.0f;
  };
  const double bin_width_rad_;
  std::vector<Accumulator> bins_;
  int view_count_ = 0;
};

}  // namespace rslam::occupancy
