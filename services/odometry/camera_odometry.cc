#include "services/odometry/camera_odometry.h"

#include <cmath>
#include <stdexcept>

#include "services/odometry/wall_direction.h"

namespace rslam::odometry {

CameraOdometry::CameraOdometry(const VisualOdometryConfig& visual, const FloorOdometryNodeConfig& floor)
    : floor_config_(floor), visual_(WithFloorCameraTilt(visual, floor)) {
  floor_config_.Validate();
  if (floor_config_.enabled) {
    boundary_ = std::make_unique<occupancy::ObstacleProfilePipeline>(floor_config_.boundary);
    floor_ = std::make_unique<FloorOdometry>(floor_config_.registration);
  }
}

void CameraOdometry::Reset() {
  visual_.Reset();
  if (floor_) floor_->Reset();
  moved_ = false;
}

const CameraOdometryFrame& CameraOdometry::Update(const cv::Mat& image, double dt_s) {
  if (!(dt_s >= 0) || !std::isfinite(dt_s))
    throw std::invalid_argument("CameraOdometry: dt must be finite and >= 0, got " + std::to_string(dt_s));
  if (floor_ && image.type() != CV_8UC3) throw std::invalid_argument("floor_odometry needs bgr8 images (CV_8UC3)");
  if (dt_s == 0) Reset();
  frame_.wall_direction.reset();
  frame_.boundary.clear();
  // A first frame's dt is ignored by the visual odometry but must be valid.
  frame_.velocity = visual_.Update(image, dt_s > 0 ? dt_s : 1.0 / visual_.config().camera_hz);
  if (floor_) FloorMotion(image, dt_s);
  return frame_;
}

void CameraOdometry::FloorMotion(const cv::Mat& image, double dt_s) {
  Velocity& velocity = frame_.velocity;
  boundary_->ProfileFromImage(image).ObstaclePoints(frame_.boundary);
  PlanarMotion prior;
  prior.dx = velocity.vtrans * dt_s;
  prior.dtheta = velocity.vrot * dt_s;
  const double hold = floor_config_.moving_difference_hold;
  const double moving_difference = moved_ && hold > 0 ? hold : floor_config_.moving_difference;
  const bool camera_moves = moving_difference > 0 && velocity.speed_difference > moving_difference;
  moved_ = camera_moves || prior.dx != 0;
  const PlanarMotion motion = floor_->Update(frame_.boundary, prior, camera_moves);
  frame_.wall_direction = WallDirection(frame_.boundary, floor_config_.wall_direction);
  if (dt_s <= 0) return;
  const double turn_in_place = visual_.config().turn_in_place_vrot_radps;
  if (floor_config_.turns_from_profiles && turn_in_place > 0 && std::abs(velocity.vrot) >= turn_in_place) return;
  // Unregistered, the floor odometry returns the prior with its constant-velocity forward step.
  velocity.vtrans = motion.dx / dt_s;
  if (motion.measured) velocity.vrot = motion.dtheta / dt_s;
}

msg::Velocity CameraOdometry::Message(double dt_s) const {
  msg::Velocity out;
  out.vtrans_mps = frame_.velocity.vtrans;
  out.vrot_radps = frame_.velocity.vrot;
  out.dt_s = dt_s;
  out.source = msg::VelocitySource::VELOCITY_VISUAL;
  if (frame_.wall_direction) {
    out.wall_seen = true;
    out.wall_direction_rad = *frame_.wall_direction;
  }
  if (floor_) {
    out.boundary_measured = true;
    out.boundary.reserve(frame_.boundary.size());
    for (const Eigen::Vector2d& p : frame_.boundary)
      out.boundary.push_back({static_cast<float>(p.x()), static_cast<float>(p.y())});
  }
  return out;
}

}  // namespace rslam::odometry
