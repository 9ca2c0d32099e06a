#include "services/occupancy/anchored_profile_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/math/pose2d_proto.h"

namespace rslam::occupancy {

namespace {

bool IsIdentity(const Pose2D& p) { return p.x == 0 && p.y == 0 && p.theta == 0; }

// Where a profile is drawn: its placement, corrected.
Pose2D Drawn(const Pose2D& placement, const ProfileCorrection& alignment) {
  return IsIdentity(alignment.correction) ? placement : Compose(placement, alignment.correction);
}

// Aligns one profile against `grid` (the profiles before it). A profile is looked at again once its
// placement has moved a cell or 0.03 rad since it last was, or when its corrected placement no
// longer fits. (The map's corrections move most anchors a little at every rebuild: searching
// every misplaced profile each time made a demo run's rebuilds take 2-5 s.)
void Align(const OccupancyGrid& grid, const RadialObstacleProfile& profile, const Pose2D& placement,
           const ProfileAlignmentConfig& config, ProfileCorrection& alignment) {
  if (config.window_m <= 0) {
    alignment = {};
    return;
  }
  if (const auto& from = alignment.searched_from) {
    const bool moved = std::hypot(from->x - placement.x, from->y - placement.y) >= grid.grid_config().resolution_m ||
                       std::abs(WrapAngle(from->theta - placement.theta)) >= 0.03;
    if (!moved && (IsIdentity(alignment.correction) ||
                   !IsMisplaced(grid, profile, Compose(placement, alignment.correction), config)))
      return;
  }
  const std::optional<Pose2D> found = AlignProfile(grid, profile, placement, config);
  alignment = {found ? Between(placement, *found) : Pose2D{}, placement};
}

}  // namespace

AnchoredProfileMap::AnchoredProfileMap(GridConfig grid, SensorModelConfig sensor, ProfileAlignmentConfig alignment)
    : grid_(std::move(grid), std::move(sensor)), alignment_(alignment) {}

void AnchoredProfileMap::AddProfile(AnchoredProfile anchored) {
  if (!IsFinite(anchored.experience_pose) || !IsFinite(anchored.offset))
    throw std::invalid_argument("experience pose or offset is not finite");
  grid_.InsertProfile(anchored.profile, Drawn(Compose(anchored.experience_pose, anchored.offset), anchored.alignment));
  profiles_.push_back(std::move(anchored));
}

void AnchoredProfileMap::AddProfile(uint64_t experience_id, const Pose2D& experience_pose,
                                    const Pose2D& robot_pose, RadialObstacleProfile profile) {
  if (!IsFinite(experience_pose) || !IsFinite(robot_pose))
    throw std::invalid_argument("experience or robot pose is not finite");
  AddProfile({experience_id, Between(experience_pose, robot_pose), experience_pose, std::move(profile), {}});
}

bool AnchoredProfileMap::IsNewView(uint64_t experience_id, const Pose2D& offset, double min_spacing_m,
                                   double min_turn_rad) const {
  if (profiles_.empty() || profiles_.back().experience_id != experience_id) return true;
  const Pose2D& last = profiles_.back().offset;
  return std::hypot(offset.x - last.x, offset.y - last.y) >= min_spacing_m ||
         std::abs(WrapAngle(offset.theta - last.theta)) >= min_turn_rad;
}

size_t AnchoredProfileMap::Rebuild(const ExperiencePoseLookup& lookup) {
  RebuildPlan plan = PlanRebuild(lookup);
  Adopt(*Replay(plan), plan);
  return plan.moved;
}

AnchoredProfileMap::RebuildPlan AnchoredProfileMap::PlanRebuild(const ExperiencePoseLookup& lookup) {
  RebuildPlan plan{grid_.grid_config(), grid_.sensor_config(), alignment_, {}, 0};
  plan.placements.reserve(profiles_.size());
  for (AnchoredProfile& p : profiles_) {
    if (const std::optional<Pose2D> pose = lookup(p.experience_id); pose && IsFinite(*pose)) {
      if (pose->x != p.experience_pose.x || pose->y != p.experience_pose.y ||
          pose->theta != p.experience_pose.theta)
        ++plan.moved;
      p.experience_pose = *pose;
    }
    plan.placements.push_back({Compose(p.experience_pose, p.offset), &p.profile, p.alignment});
  }
  return plan;
}

std::optional<OccupancyGrid> AnchoredProfileMap::Replay(RebuildPlan& plan, std::stop_token stop) {
  OccupancyGrid grid(plan.grid, plan.sensor);
  for (Placement& p : plan.placements) {
    if (stop.stop_requested()) return std::nullopt;
    Align(grid, *p.profile, p.pose, plan.alignment, p.alignment);
    grid.InsertProfile(*p.profile, Drawn(p.pose, p.alignment));
  }
  return grid;
}

void AnchoredProfileMap::Adopt(OccupancyGrid grid, const RebuildPlan& plan) {
  for (size_t i = 0; i < plan.placements.size(); ++i) profiles_[i].alignment = plan.placements[i].alignment;
  for (size_t i = plan.placements.size(); i < profiles_.size(); ++i)
    grid.InsertProfile(profiles_[i].profile,
                       Drawn(Compose(profiles_[i].experience_pose, profiles_[i].offset), profiles_[i].alignment));
  grid_ = std::move(grid);
}

size_t AnchoredProfileMap::AlignedProfiles() const {
  return static_cast<size_t>(std::count_if(profiles_.begin(), profiles_.end(), [](const AnchoredProfile& p) {
    return !IsIdentity(p.alignment.correction);
  }));
}

proto::OccupancyState AnchoredProfileMap::ToProto() const {
  proto::OccupancyState state;
  auto* g = state.mutable_grid();
  const GridConfig& gc = grid_.grid_config();
  const SensorModelConfig& sc = grid_.sensor_config();
  g->set_resolution_m(gc.resolution_m);
  g->set_width(gc.width);
  g->set_height(gc.height);
  g->set_origin_x_m(gc.origin_x_m);
  g->set_origin_y_m(gc.origin_y_m);
  g->set_hit_probability(sc.hit_probability);
  g->set_miss_probability(sc.miss_probability);
  g->set_blind_probability(sc.blind_probability);
  g->set_min_probability(sc.min_probability);
  g->set_max_probability(sc.max_probability);
  g->set_reliable_range_m(sc.reliable_range_m);
  g->set_footprint_radius_m(sc.footprint_radius_m);
  for (const AnchoredProfile& p : profiles_) {
    auto* out = state.add_profiles();
    out->set_experience_id(p.experience_id);
    SavePose(p.offset, out->mutable_offset());
    SavePose(p.experience_pose, out->mutable_experience_pose());
    out->set_first_bearing_rad(p.profile.first_bearing_rad);
    out->set_bin_width_rad(p.profile.bin_width_rad);
    std::string status;
    for (const RopBin& b : p.profile.bins) {
      out->add_range_m(b.range_m);
      out->add_nearest_visible_m(b.nearest_visible_m);
      status.push_back(static_cast<char>(b.status));
    }
    out->set_status(std::move(status));
  }
  return state;
}

AnchoredProfileMap AnchoredProfileMap::FromProto(const proto::OccupancyState& state) {
  const auto& g = state.grid();
  GridConfig gc{g.resolution_m(), g.width(), g.height(), g.origin_x_m(), g.origin_y_m()};
  SensorModelConfig sc{g.hit_probability(), g.miss_probability(), g.blind_probability(),
                       g.min_probability(), g.max_probability(), g.reliable_range_m(), g.footprint_radius_m()};
  try {
    gc.Validate();
    sc.Validate();
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("occupancy state has bad grid parameters: ") + e.what());
  }
  std::deque<AnchoredProfile> profiles;
  for (int i = 0; i < state.profiles_size(); ++i) {
    const auto& in = state.profiles(i);
    const std::string where = "occupancy state profile " + std::to_string(i) + ": ";
    const size_t n = in.status().size();
    if (static_cast<size_t>(in.range_m_size()) != n || static_cast<size_t>(in.nearest_visible_m_size()) != n)
      throw std::invalid_argument(where + "ranges and statuses differ in length");
    AnchoredProfile p;
    p.experience_id = in.experience_id();
    p.offset = LoadPose(in.offset());
    p.experience_pose = LoadPose(in.experience_pose());
    if (!IsFinite(p.offset) || !IsFinite(p.experience_pose)) throw std::invalid_argument(where + "pose not finite");
    p.profile.first_bearing_rad = in.first_bearing_rad();
    p.profile.bin_width_rad = in.bin_width_rad();
    if (!std::isfinite(p.profile.first_bearing_rad) || !std::isfinite(p.profile.bin_width_rad) ||
        p.profile.bin_width_rad <= 0)
      throw std::invalid_argument(where + "bad bearings");
    p.profile.bins.resize(n);
    for (size_t k = 0; k < n; ++k) {
      const auto status = static_cast<uint8_t>(in.status()[k]);
      if (status > static_cast<uint8_t>(BinStatus::kBlind)) throw std::invalid_argument(where + "unknown bin status");
      const float r = in.range_m(static_cast<int>(k)), nv = in.nearest_visible_m(static_cast<int>(k));
      if (!std::isfinite(r) || r < 0 || !std::isfinite(nv) || nv < 0) throw std::invalid_argument(where + "bad range");
      p.profile.bins[k] = RopBin{r, nv, static_cast<BinStatus>(status)};
    }
    profiles.push_back(std::move(p));
  }
  AnchoredProfileMap map(gc, sc);
  map.profiles_ = std::move(profiles);
  map.Rebuild([](uint64_t) { return std::nullopt; });
  return map;
}

}  // namespace rslam::occupancy
