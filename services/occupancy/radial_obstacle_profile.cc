#include "services/occupancy/radial_obstacle_profile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rslam::occupancy {

void RopConfig::Validate() const {
  Require(std::isfinite(bin_width_deg) && bin_width_deg > 0 && bin_width_deg <= 30, "bin_width_deg",
          "must be in (0, 30]");
  Require(std::isfinite(scan_range_m) && scan_range_m > 0 && scan_range_m <= 100, "scan_range_m",
          "must be in (0, 100]");
  Require(std::isfinite(range_step_m) && range_step_m > 0 && range_step_m <= scan_range_m,
          "range_step_m", "must be in (0, scan_range_m]");
}

RopExtractor::RopExtractor(RopConfig config, const InversePerspectiveMap& ipm)
    : config_(std::move(config)), width_(ipm.camera().width), height_(ipm.camera().height) {
  config_.Validate();
  // The widest bearing at which any pixel sees the floor within the scan range.
  double widest = 0.0;
  for (int v = 0; v < height_; ++v)
    for (int u = 0; u < width_; ++u)
      if (auto p = ipm.FloorPoint(u, v)) {
        if (std::hypot(p->x, p->y) <= config_.scan_range_m && p->x > 0)
          widest = std::max<double>(widest, std::abs(std::atan2(p->y, p->x)));
      }
  const double bin_width = config_.bin_width_deg * M_PI / 180.0;
  const int half_bins = static_cast<int>(std::ceil(widest / bin_width));
  first_bearing_rad_ = -half_bins * bin_width;
  rays_.resize(2 * half_bins);
  for (size_t i = 0; i < rays_.size(); ++i) {
    const double bearing = first_bearing_rad_ + (i + 0.5) * bin_width;
    const double c = std::cos(bearing), s = std::sin(bearing);
    for (double r = config_.range_step_m; r <= config_.scan_range_m + 1e-9; r += config_.range_step_m) {
      const auto pixel = ipm.ProjectFloorToPixel(r * c, r * s);
      if (!pixel) continue;
      const int u = static_cast<int>(std::lround(pixel->x));
      const int v = static_cast<int>(std::lround(pixel->y));
      if (u < 0 || v < 0 || u >= width_ || v >= height_) {
        // Once the scan has entered the image, leaving it ends the visible part of this ray.
        if (!rays_[i].range_m.empty()) break;
        continue;
      }
      rays_[i].pixel_index.push_back(v * width_ + u);
      rays_[i].range_m.push_back(static_cast<float>(r));
    }
  }
}

RadialObstacleProfile RopExtractor::Extract(const cv::Mat& floor_mask) const {
  if (floor_mask.empty() || floor_mask.type() != CV_8UC1 || floor_mask.cols != width_ ||
      floor_mask.rows != height_)
    throw std::invalid_argument("floor mask must be CV_8U of the camera's size");
  const cv::Mat mask = floor_mask.isContinuous() ? floor_mask : floor_mask.clone();
  const uchar* data = mask.ptr<uchar>(0);
  RadialObstacleProfile profile;
  profile.first_bearing_rad = first_bearing_rad_;
  profile.bin_width_rad = config_.bin_width_deg * M_PI / 180.0;
  profile.bins.resize(rays_.size());
  for (size_t i = 0; i < rays_.size(); ++i) {
    const Ray& ray = rays_[i];
    RopBin& bin = profile.bins[i];
    if (ray.pixel_index.empty()) continue;  // kUnobserved
    bin.nearest_visible_m = ray.range_m.front();
    size_t k = 0;
    while (k < ray.pixel_index.size() && data[ray.pixel_index[k]]) ++k;
    if (k == ray.pixel_index.size()) {
      bin.status = BinStatus::kFree;
      bin.range_m = ray.range_m.back();
    } else if (k == 0) {
      bin.status = BinStatus::kBlind;
      bin.range_m = ray.range_m.front();
    } else {
      bin.status = BinStatus::kObstacle;
      bin.range_m = 0.5f * (ray.range_m[k - 1] + ray.range_m[k]);  // the boundary lies between the two
    }
  }
  return profile;
}

PirouetteProfileBuilder::PirouetteProfileBuilder(double bin_width_deg)
    : bin_width_rad_(bin_width_deg * M_PI / 180.0) {
  if (!std::isfinite(bin_width_deg) || bin_width_deg <= 0 || bin_width_deg > 30)
    throw std::invalid_argument("pirouette bin width must be in (0, 30] degrees");
  bins_.resize(static_cast<size_t>(std::lround(2 * M_PI / bin_width_rad_)));
}

void PirouetteProfileBuilder::Clear() {
  std::fill(bins_.begin(), bins_.end(), Accumulator{});
  view_count_ = 0;
}

void PirouetteProfileBuilder::AddView(const RadialObstacleProfile& view, double heading_rad) {
  if (!std::isfinite(heading_rad)) throw std::invalid_argument("view heading is not finite");
  const int n = static_cast<int>(bins_.size());
  for (size_t i = 0; i < view.bins.size(); ++i) {
    const RopBin& in = view.bins[i];
    if (in.status == BinStatus::kUnobserved) continue;
    const double bearing = heading_rad + view.BinCentre(i);
    int out = static_cast<int>(std::floor((bearing + M_PI) / bin_width_rad_)) % n;
    if (out < 0) out += n;
    Accumulator& acc = bins_[out];
    acc.nearest_visible = acc.obstacle_ranges.empty() && acc.free_ranges.empty() && acc.blind == 0
                              ? in.nearest_visible_m
                              : std::min(acc.nearest_visible, in.nearest_visible_m);
    switch (in.status) {
      case BinStatus::kObstacle: acc.obstacle_ranges.push_back(in.range_m); break;
      case BinStatus::kFree: acc.free_ranges.push_back(in.range_m); break;
      case BinStatus::kBlind: ++acc.blind; break;
      case BinStatus::kUnobserved: break;
    }
  }
  ++view_count_;
}

RadialObstacleProfile PirouetteProfileBuilder::Build() const {
  RadialObstacleProfile profile;
  profile.first_bearing_rad = -M_PI;
  profile.bin_width_rad = bin_width_rad_;
  profile.bins.resize(bins_.size());
  for (size_t i = 0; i < bins_.size(); ++i) {
    const Accumulator& acc = bins_[i];
    RopBin& bin = profile.bins[i];
    bin.nearest_visible_m = acc.nearest_visible;
    double obstacle_mean = 0.0;
    for (float r : acc.obstacle_ranges) obstacle_mean += r;
    if (!acc.obstacle_ranges.empty()) obstacle_mean /= acc.obstacle_ranges.size();
    const auto contradicting = std::count_if(acc.free_ranges.begin(), acc.free_ranges.end(),
                                             [&](float r) { return r >= obstacle_mean; });
    if (!acc.obstacle_ranges.empty() && static_cast<long>(acc.obstacle_ranges.size()) >= contradicting) {
      bin.status = BinStatus::kObstacle;
      bin.range_m = static_cast<float>(obstacle_mean);
    } else if (!acc.free_ranges.empty()) {
      bin.status = BinStatus::kFree;
      bin.range_m = *std::max_element(acc.free_ranges.begin(), acc.free_ranges.end());
    } else if (acc.blind > 0) {
      bin.status = BinStatus::kBlind;
      bin.range_m = acc.nearest_visible;
    }
  }
  return profile;
}

void RadialObstacleProfile::ObstaclePoints(std::vector<Eigen::Vector2d>& out) const {
  out.clear();
  for (size_t i = 0; i < bins.size(); ++i) {
    if (bins[i].status != BinStatus::kObstacle) continue;
    const double bearing = BinCentre(i), range = bins[i].range_m;
    out.emplace_back(range * std::cos(bearing), range * std::sin(bearing));
  }
}

}  // namespace rslam::occupancy
