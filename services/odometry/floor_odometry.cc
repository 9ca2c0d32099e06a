#include "services/odometry/floor_odometry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/math/angle.h"

namespace rslam::odometry {

namespace {

// Pose (x, y, theta) composed with a motion expressed in that pose's frame.
Eigen::Vector3d Compose(const Eigen::Vector3d& pose, double dx, double dy, double dtheta) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  return {pose.x() + c * dx - s * dy, pose.y() + s * dx + c * dy, pose.z() + dtheta};
}

// The motion from pose a to pose b, in a's frame.
PlanarMotion Between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  const double ex = b.x() - a.x(), ey = b.y() - a.y();
  PlanarMotion m;
  m.dx = c * ex + s * ey;
  m.dy = -s * ex + c * ey;
  m.dtheta = WrapAngle(b.z() - a.z());
  return m;
}

}  // namespace

FloorOdometry::FloorOdometry(FloorOdometryConfig config) : config_(std::move(config)) {
  config_.Validate();
  moving_dx_.resize(config_.coast_speed_steps);
}

void FloorOdometry::Reset() {
  has_key_ = false;
  last_registered_ = false;
  moving_dx_count_ = 0;
  coast_step_ = 0.0;
  frames_since_moving_dx_ = -1;
  was_moving_ = false;
  still_run_ = 0;
  key_ = BoundaryScan{};
  key_to_robot_.setZero();
}

void FloorOdometry::RecordMovingStep(double dx) {
  moving_dx_[moving_dx_count_ % moving_dx_.size()] = dx;
  ++moving_dx_count_;
  frames_since_moving_dx_ = 0;
  const auto n = static_cast<ptrdiff_t>(std::min<uint64_t>(moving_dx_count_, moving_dx_.size()));
  std::vector<double> steps(moving_dx_.begin(), moving_dx_.begin() + n);
  std::nth_element(steps.begin(), steps.begin() + n / 2, steps.end());
  coast_step_ = steps[n / 2];
}

void FloorOdometry::MakeKeyFrame(std::vector<Eigen::Vector2d>&& points) {
  key_ = BoundaryScan::FromPoints(std::move(points));
  key_to_robot_.setZero();
  has_key_ = true;
}

Alignment FloorOdometry::Register(std::span<const Eigen::Vector2d> points, const Eigen::Vector3d& predicted,
                                  const Eigen::Vector3d& prior) const {
  AlignmentOptions options;
  options.max_pair_distance_m = config_.max_pair_distance_m;
  options.iterations = config_.iterations;
  options.min_pairs = config_.min_points;
  options.lateral_prior = config_.lateral_prior;
  options.rotation_prior = config_.rotation_prior;
  options.min_forward_constraint = config_.min_constraint;
  return AlignToScan(key_, points, predicted, prior, options);
}

PlanarMotion FloorOdometry::Update(std::span<const Eigen::Vector2d> boundary, const PlanarMotion& given_prior,
                                   bool camera_moves) {
  if (!std::isfinite(given_prior.dx) || !std::isfinite(given_prior.dy) || !std::isfinite(given_prior.dtheta))
    throw std::invalid_argument("FloorOdometry: the prior motion is not finite");
  const bool straight = std::abs(given_prior.dtheta) < config_.straight_max_turn_rad;
  bool moving = given_prior.dx != 0.0 || camera_moves;
  if (moving) {
    still_run_ = 0;
  } else if (was_moving_ && straight && still_run_ < config_.coast_still_frames) {
    moving = true;
    ++still_run_;
  }
  const bool after_straight_move = was_moving_;
  was_moving_ = moving && straight;
  PlanarMotion prior = given_prior;
  if (frames_since_moving_dx_ >= 0) ++frames_since_moving_dx_;
  const bool can_coast = frames_since_moving_dx_ >= 0 && frames_since_moving_dx_ <= config_.coast_frames;
  const double coast_dx = frames_since_moving_dx_ >= 0 ? coast_step_ : 0.0;
  if (moving && straight && can_coast) prior.dx = coast_dx;
  std::vector<Eigen::Vector2d> points;
  points.reserve(boundary.size());
  for (const Eigen::Vector2d& p : boundary) {
    if (!p.allFinite()) throw std::invalid_argument("FloorOdometry: a boundary point is not finite");
    if (p.norm() <= config_.max_range_m) points.push_back(p);
  }
  PlanarMotion out = prior;
  out.measured = false;
  out.pairs = 0;
  if (!has_key_ || static_cast<int>(key_.points.size()) < config_.min_points) {
    MakeKeyFrame(std::move(points));
    last_registered_ = false;
    return out;
  }
  const Eigen::Vector3d previous = key_to_robot_;
  // Seeds: the prior; the last registered motion (constant velocity), right when the column
  // profiles are fooled (repeated texture can fake a fast turn during a straight move); and the
  // last registered forward step with the prior's turn, right when the profiles miss that the
  // robot drives (a plain wall ahead looks the same from a little closer).
  std::vector<PlanarMotion> seeds = {prior};
  if (last_registered_) seeds.push_back(last_motion_);
  if (frames_since_moving_dx_ >= 0 && prior.dx != coast_dx) {  // a seed may be any age
    PlanarMotion driving_on = prior;
    driving_on.dx = coast_dx;
    seeds.push_back(driving_on);
  }
  Alignment best;
  const Eigen::Vector3d held = Compose(previous, prior.dx, prior.dy, prior.dtheta);
  for (const PlanarMotion& seed : seeds) {
    const Alignment r = Register(points, Compose(previous, seed.dx, seed.dy, seed.dtheta), held);
    if (!r.ok) continue;
    // The closer fit wins, unless it pairs up clearly fewer points (a wrong seed can still
    // settle where a few points happen to fit).
    const bool better_fit = r.mean_residual2 < best.mean_residual2 && r.pairs * 5 >= best.pairs * 4;
    const bool many_more_pairs = best.pairs * 5 < r.pairs * 4;
    if (!best.ok || better_fit || many_more_pairs) best = r;
  }
  out.pairs = best.pairs;
  const bool registered = best.ok;
  last_registered_ = registered;
  if (registered) {
    out = Between(previous, best.pose);
    out.measured = true;
    out.pairs = best.pairs;
    key_to_robot_ = best.pose;
    last_motion_ = out;
    // A still prior taken as moving that registers standing still ends the motion.
    if (still_run_ > 0 && std::abs(out.dx) < 0.5 * coast_dx) was_moving_ = false;
    // The speed comes from forward steps of frames the prior itself calls moving, straight, after
    // a straight moving frame: a turn's step is no speed, nor the camera settling as a turn ends.
    if (given_prior.dx != 0.0 && after_straight_move && out.dx > 0 &&
        std::abs(out.dtheta) < config_.straight_max_turn_rad)
      RecordMovingStep(out.dx);
  } else {
    key_to_robot_ = Compose(previous, prior.dx, prior.dy, prior.dtheta);
  }
  if (!registered || key_to_robot_.head<2>().norm() >= config_.keyframe_translation_m ||
      std::abs(key_to_robot_.z()) >= config_.keyframe_rotation_rad) {
    const int pairs = out.pairs;
    MakeKeyFrame(std::move(points));
    out.pairs = pairs;
  }
  return out;
}

}  // namespace rslam::odometry
