#include "services/occupancy/profile_message.h"

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

msg::OccupancyGrid GridToMessage(const OccupancyGrid& grid) {
  msg::OccupancyGrid out{};
  out.width = static_cast<uint32_t>(grid.width());
  out.height = static_cast<uint32_t>(grid.height());
  out.resolution_m = static_cast<float>(grid.grid_config().resolution_m);
  out.origin_x_m = grid.grid_config().origin_x_m;
  out.origin_y_m = grid.grid_config().origin_y_m;
  out.cells = grid.ToRosCells();
  return out;
}

}  // namespace rslam::occupancy
