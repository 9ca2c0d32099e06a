#include "services/occupancy/profile_message.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rslam::occupancy {

namespace {

msg::ProfileBinStatus ToMessage(BinStatus status) {
  switch (status) {
    case BinStatus::kObstacle: return msg::ProfileBinStatus::PROFILE_BIN_OBSTACLE;
    case BinStatus::kFree: return msg::ProfileBinStatus::PROFILE_BIN_FREE;
    case BinStatus::kBlind: return msg::ProfileBinStatus::PROFILE_BIN_BLIND;
    case BinStatus::kUnobserved: break;
  }
  return msg::ProfileBinStatus::PROFILE_BIN_UNOBSERVED;
}

BinStatus FromMessage(msg::ProfileBinStatus status, size_t index) {
  switch (status) {
    case msg::ProfileBinStatus::PROFILE_BIN_UNOBSERVED: return BinStatus::kUnobserved;
    case msg::ProfileBinStatus::PROFILE_BIN_OBSTACLE: return BinStatus::kObstacle;
    case msg::ProfileBinStatus::PROFILE_BIN_FREE: return BinStatus::kFree;
    case msg::ProfileBinStatus::PROFILE_BIN_BLIND: return BinStatus::kBlind;
  }
  throw std::invalid_argument("bin " + std::to_string(index) + " has an unknown status " +
                              std::to_string(static_cast<int>(status)));
}

}  // namespace

msg::ObstacleProfile ProfileToMessage(const msg::Header& header, const AnchoredProfile& anchored, float max_range_m) {
  msg::ObstacleProfile out;
  out.header = header;
  out.experience_id = static_cast<uint32_t>(anchored.experience_id);
  out.offset_x_m = anchored.offset.x;
  out.offset_y_m = anchored.offset.y;
  out.offset_theta_rad = anchored.offset.theta;
  const RadialObstacleProfile& rop = anchored.profile;
  out.bearing_min_rad = static_cast<float>(rop.BinCentre(0));
  out.bearing_step_rad = static_cast<float>(rop.bin_width_rad);
  out.max_range_m = max_range_m;
  out.bins.reserve(rop.bins.size());
  for (const RopBin& bin : rop.bins) out.bins.push_back({ToMessage(bin.status), bin.range_m, bin.nearest_visible_m});
  return out;
}

RadialObstacleProfile ProfileFromMessage(const msg::ObstacleProfile& message) {
  if (!std::isfinite(message.bearing_min_rad) || !std::isfinite(message.bearing_step_rad) || message.bearing_step_rad <= 0)
    throw std::invalid_argument("bearings are not finite, or the step is not positive");
  if (!std::isfinite(message.max_range_m) || message.max_range_m <= 0)
    throw std::invalid_argument("max_range_m is not positive");
  RadialObstacleProfile rop;
  rop.bin_width_rad = message.bearing_step_rad;
  rop.first_bearing_rad = message.bearing_min_rad - 0.5 * rop.bin_width_rad;
  rop.bins.reserve(message.bins.size());
  for (size_t i = 0; i < message.bins.size(); ++i) {
    const msg::ProfileBin& in = message.bins[i];
    RopBin bin{in.range_m, in.nearest_visible_m, FromMessage(in.status, i)};
    if (!std::isfinite(bin.range_m) || !std::isfinite(bin.nearest_visible_m) || bin.range_m < 0 || bin.nearest_visible_m < 0)
      throw std::invalid_argument("bin " + std::to_string(i) + " has a negative or non-finite range");
    rop.bins.push_back(bin);
  }
  return rop;
}

CellWindow GridMessageWindow(const OccupancyGrid& grid) {
  const std::optional<CellWindow> seen = grid.SeenWindow();
  if (!seen) return {0, 0, grid.width(), grid.height()};
  const int margin = static_cast<int>(std::ceil(kGridMessageMarginM / grid.grid_config().resolution_m));
  const int b = kGridMessageBlockCells;
  const int x0 = std::max(0, seen->x0 - margin) / b * b, y0 = std::max(0, seen->y0 - margin) / b * b;
  const int x1 = std::min(grid.width(), (seen->x0 + seen->width + margin + b - 1) / b * b);
  const int y1 = std::min(grid.height(), (seen->y0 + seen->height + margin + b - 1) / b * b);
  return {x0, y0, x1 - x0, y1 - y0};
}

msg::OccupancyGrid GridToMessage(const OccupancyGrid& grid) {
  const CellWindow window = GridMessageWindow(grid);
  const GridConfig& config = grid.grid_config();
  msg::OccupancyGrid out{};
  out.width = static_cast<uint32_t>(window.width);
  out.height = static_cast<uint32_t>(window.height);
  out.resolution_m = static_cast<float>(config.resolution_m);
  out.origin_x_m = config.origin_x_m + window.x0 * config.resolution_m;
  out.origin_y_m = config.origin_y_m + window.y0 * config.resolution_m;
  out.cells = grid.ToRosCells(window);
  return out;
}

}  // namespace rslam::occupancy
