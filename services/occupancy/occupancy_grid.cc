#include "services/occupancy/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rslam::occupancy {

double LogOddsFromProbability(double p) { return std::log(p / (1.0 - p)); }
double ProbabilityFromLogOdds(double l) { return 1.0 / (1.0 + std::exp(-l)); }

void GridConfig::Validate() const {
  Require(std::isfinite(resolution_m) && resolution_m > 0, "resolution_m", "must be positive");
  Require(width > 0 && width <= 20000, "width", "must be in 1..20000");
  Require(height > 0 && height <= 20000, "height", "must be in 1..20000");
  Require(std::isfinite(origin_x_m), "origin_x_m", "must be finite");
  Require(std::isfinite(origin_y_m), "origin_y_m", "must be finite");
}

void SensorModelConfig::Validate() const {
  auto prob = [](double p) { return std::isfinite(p) && p > 0.0 && p < 1.0; };
  Require(prob(min_probability) && min_probability < 0.5, "min_probability", "must be in (0, 0.5)");
  Require(prob(max_probability) && max_probability > 0.5, "max_probability", "must be in (0.5, 1)");
  Require(prob(hit_probability) && hit_probability > 0.5, "hit_probability", "must be in (0.5, 1)");
  Require(prob(miss_probability) && miss_probability < 0.5, "miss_probability", "must be in (0, 0.5)");
  Require(prob(blind_probability) && blind_probability >= 0.5, "blind_probability", "must be in [0.5, 1)");
  Require(std::isfinite(reliable_range_m) && reliable_range_m > 0, "reliable_range_m", "must be positive");
  Require(std::isfinite(footprint_radius_m) && footprint_radius_m >= 0 && footprint_radius_m <= 5,
          "footprint_radius_m", "must be in [0, 5]");
}

OccupancyGrid::OccupancyGrid(GridConfig grid, SensorModelConfig sensor)
    : grid_(std::move(grid)), sensor_(std::move(sensor)) {
  grid_.Validate();
  sensor_.Validate();
  log_odds_min_ = LogOddsFromProbability(sensor_.min_probability);
  log_odds_max_ = LogOddsFromProbability(sensor_.max_probability);
  const double hit = LogOddsFromProbability(sensor_.hit_probability);
  const double miss = LogOddsFromProbability(sensor_.miss_probability);
  const double blind = std::min(LogOddsFromProbability(sensor_.blind_probability), log_odds_max_);
  hit_table_.resize(kUpdateMarker);
  miss_table_.resize(kUpdateMarker);
  blind_table_.resize(kUpdateMarker);
  percent_table_.resize(kUpdateMarker);
  for (uint32_t v = 0; v < kUpdateMarker; ++v) {
    const double l = ValueToLogOdds(static_cast<uint16_t>(v));
    hit_table_[v] = LogOddsToValue(l + hit) + kUpdateMarker;
    miss_table_[v] = LogOddsToValue(l + miss) + kUpdateMarker;
    // The blind area only says "something is in there": it never overrides evidence.
    blind_table_[v] = (v == kUnknownValue ? LogOddsToValue(blind) : static_cast<uint16_t>(v)) + kUpdateMarker;
    percent_table_[v] =
        v == kUnknownValue ? int8_t{-1} : static_cast<int8_t>(std::lround(100.0 * ProbabilityFromLogOdds(l)));
  }
  values_.assign(static_cast<size_t>(grid_.width) * grid_.height, kUnknownValue);
  if (sensor_.footprint_radius_m > 0) footprint_.assign(values_.size(), 0);  // off: no layer
}

double OccupancyGrid::ValueToLogOdds(uint16_t value) const {
  if (value == kUnknownValue) return 0.0;
  return log_odds_min_ + (value - 1) * (log_odds_max_ - log_odds_min_) / (kMaxValue - 1);
}

uint16_t OccupancyGrid::LogOddsToValue(double log_odds) const {
  const double clamped = std::clamp(log_odds, log_odds_min_, log_odds_max_);
  return static_cast<uint16_t>(
      1 + std::lround((clamped - log_odds_min_) / (log_odds_max_ - log_odds_min_) * (kMaxValue - 1)));
}

double OccupancyGrid::Probability(CellIndex c) const {
  if (UnderFootprint(c)) return sensor_.min_probability;
  const uint16_t v = Value(c);
  return v == kUnknownValue ? 0.5 : ProbabilityFromLogOdds(ValueToLogOdds(v));
}

CellIndex OccupancyGrid::CellOf(double x_m, double y_m) const {
  return {static_cast<int>(std::floor((x_m - grid_.origin_x_m) / grid_.resolution_m)),
          static_cast<int>(std::floor((y_m - grid_.origin_y_m) / grid_.resolution_m))};
}

void OccupancyGrid::Clear() {
  std::fill(values_.begin(), values_.end(), kUnknownValue);
  std::fill(footprint_.begin(), footprint_.end(), 0);
  seen_x0_ = seen_y0_ = 0;
  seen_x1_ = seen_y1_ = -1;
}

void OccupancyGrid::WidenSeen(int x0, int y0, int x1, int y1) {
  if (seen_x1_ < seen_x0_) {
    seen_x0_ = x0, seen_y0_ = y0, seen_x1_ = x1, seen_y1_ = y1;
    return;
  }
  seen_x0_ = std::min(seen_x0_, x0), seen_y0_ = std::min(seen_y0_, y0);
  seen_x1_ = std::max(seen_x1_, x1), seen_y1_ = std::max(seen_y1_, y1);
}

std::optional<CellWindow> OccupancyGrid::SeenWindow() const {
  if (seen_x1_ < seen_x0_) return std::nullopt;
  return CellWindow{seen_x0_, seen_y0_, seen_x1_ - seen_x0_ + 1, seen_y1_ - seen_y0_ + 1};
}

// Cells whose centre lies within footprint_radius_m of (gx, gy) (grid units).
void OccupancyGrid::MarkFootprint(double gx, double gy) {
  const double r = sensor_.footprint_radius_m / grid_.resolution_m;
  const int x0 = std::max(0, static_cast<int>(std::floor(gx - r)));
  const int x1 = std::min(grid_.width - 1, static_cast<int>(std::floor(gx + r)));
  const int y0 = std::max(0, static_cast<int>(std::floor(gy - r)));
  const int y1 = std::min(grid_.height - 1, static_cast<int>(std::floor(gy + r)));
  if (x0 > x1 || y0 > y1) return;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double ex = x + 0.5 - gx, ey = y + 0.5 - gy;
      if (ex * ex + ey * ey <= r * r) footprint_[static_cast<size_t>(y) * grid_.width + x] = 1;
    }
  WidenSeen(x0, y0, x1, y1);
}

inline void OccupancyGrid::ApplyTable(size_t index, const uint16_t* table) {
  uint16_t& v = values_[index];
  if (v >= kUpdateMarker) return;  // already updated by this profile
  v = table[v];
  updated_.push_back(index);
}

// Cells from (x0, y0) to (x1, y1) in grid units, by Bresenham's line; the last cell gets a hit when
// end_is_hit, every other cell a miss (or the blind value). Cells outside the grid are skipped.
void OccupancyGrid::ApplyRay(double x0, double y0, double x1, double y1, bool end_is_hit,
                             const uint16_t* miss_table) {
  int cx = static_cast<int>(std::floor(x0)), cy = static_cast<int>(std::floor(y0));
  const int ex = static_cast<int>(std::floor(x1)), ey = static_cast<int>(std::floor(y1));
  const int dx = std::abs(ex - cx), dy = -std::abs(ey - cy);
  const int sx = cx < ex ? 1 : -1, sy = cy < ey ? 1 : -1;
  int err = dx + dy;
  const unsigned w = static_cast<unsigned>(grid_.width), h = static_cast<unsigned>(grid_.height);
  while (true) {
    const bool last = cx == ex && cy == ey;
    if (static_cast<unsigned>(cx) < w && static_cast<unsigned>(cy) < h) {
      ApplyTable(static_cast<size_t>(cy) * w + cx, last && end_is_hit ? hit_table_.data() : miss_table);
    }
    if (last) break;
    const int e2 = 2 * err;
    if (e2 >= dy) { err += dy; cx += sx; }
    if (e2 <= dx) { err += dx; cy += sy; }
  }
}

int64_t OccupancyGrid::InsertProfile(const RadialObstacleProfile& profile, const Pose2D& robot_pose) {
  if (!IsFinite(robot_pose)) throw std::invalid_argument("robot pose is not finite");
  if (!std::isfinite(profile.first_bearing_rad) || !std::isfinite(profile.bin_width_rad) ||
      profile.bin_width_rad <= 0)
    throw std::invalid_argument("profile bearings are not finite or bin width is not positive");
  updated_.clear();
  const double inv_res = 1.0 / grid_.resolution_m;
  const double gx = (robot_pose.x - grid_.origin_x_m) * inv_res;
  const double gy = (robot_pose.y - grid_.origin_y_m) * inv_res;
  const double reliable = sensor_.reliable_range_m;
  double lo_x = gx, lo_y = gy, hi_x = gx, hi_y = gy;  // the rays' bounds (SeenWindow)
  for (size_t i = 0; i < profile.bins.size(); ++i) {
    const RopBin& bin = profile.bins[i];
    if (bin.status == BinStatus::kUnobserved) continue;
    if (!std::isfinite(bin.range_m) || bin.range_m < 0 || !std::isfinite(bin.nearest_visible_m))
      throw std::invalid_argument("profile bin " + std::to_string(i) + " has a bad range");
    double r = 0.0;
    bool end_is_hit = false;
    const uint16_t* table = miss_table_.data();
    switch (bin.status) {
      case BinStatus::kObstacle:
        if (bin.range_m <= reliable) {
          r = HitRange(bin.range_m);
          end_is_hit = true;
          break;
        }
        [[fallthrough]];  // an obstacle beyond the reliable range: free up to that range only
      case BinStatus::kFree: r = std::min<double>(bin.range_m, reliable); break;
      case BinStatus::kBlind:
        r = std::min<double>(bin.nearest_visible_m, reliable);
        table = blind_table_.data();
        break;
      case BinStatus::kUnobserved: continue;
    }
    const double angle = robot_pose.theta + profile.BinCentre(i);
    const double ex = gx + std::cos(angle) * inv_res * r, ey = gy + std::sin(angle) * inv_res * r;
    ApplyRay(gx, gy, ex, ey, end_is_hit, table);
    lo_x = std::min(lo_x, ex), lo_y = std::min(lo_y, ey), hi_x = std::max(hi_x, ex), hi_y = std::max(hi_y, ey);
  }
  for (size_t index : updated_) values_[index] -= kUpdateMarker;
  if (!updated_.empty()) {  // every ray runs from the robot to its end: their bounds hold the cells updated
    WidenSeen(std::max(0, static_cast<int>(std::floor(lo_x))), std::max(0, static_cast<int>(std::floor(lo_y))),
              std::min(grid_.width - 1, static_cast<int>(std::floor(hi_x))),
              std::min(grid_.height - 1, static_cast<int>(std::floor(hi_y))));
  }
  if (sensor_.footprint_radius_m > 0) MarkFootprint(gx, gy);
  return static_cast<int64_t>(updated_.size());
}

std::vector<int8_t> OccupancyGrid::ToRosCells(const CellWindow& window) const {
  if (window.width <= 0 || window.height <= 0 || window.x0 < 0 || window.y0 < 0 ||
      window.x0 + window.width > grid_.width || window.y0 + window.height > grid_.height)
    throw std::invalid_argument("cell window is empty or not inside the grid");
  const auto footprint_percent = static_cast<int8_t>(std::lround(100.0 * sensor_.min_probability));
  std::vector<int8_t> out(static_cast<size_t>(window.width) * window.height);
  for (int y = 0; y < window.height; ++y) {
    const size_t from = static_cast<size_t>(window.y0 + y) * grid_.width + window.x0;
    int8_t* row = out.data() + static_cast<size_t>(y) * window.width;
    std::transform(values_.begin() + from, values_.begin() + from + window.width, row,
                   [this](uint16_t v) { return percent_table_[v]; });
    if (!footprint_.empty())
      for (int x = 0; x < window.width; ++x)
        if (footprint_[from + x]) row[x] = footprint_percent;
  }
  return out;
}

}  // namespace rslam::occupancy
