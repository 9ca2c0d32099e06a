#include "services/odometry/odometry_node.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "services/camera/image_message.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/odometry/floor_odometry.h"
#include "services/odometry/visual_odometry.h"
#include "services/odometry/wall_direction.h"

namespace rslam::odometry {

class OdometryNode::Impl {
 public:
  Impl(ServiceContext& context, const Config& config)
      : context_(context), config_(config), odometry_(config.visual) {
    if (config.floor.enabled) {
      boundary_ = std::make_unique<occupancy::ObstacleProfilePipeline>(config.floor.boundary);
      floor_ = std::make_unique<FloorOdometry>(config.floor.registration);
    }
  }

  void Start(const std::shared_ptr<Impl>& self, std::vector<std::shared_ptr<void>>& subscriptions) {
    publisher_ = context_.Advertise(bus::topics::kOdometryVelocity);
    std::weak_ptr<Impl> weak = self;
    if (config_.use_wheel_odometry) {
      subscriptions.push_back(
          context_.Subscribe<msg::Velocity>(bus::topics::kWheelOdometry, [weak](const msg::Velocity& v) {
            if (auto impl = weak.lock()) impl->OnWheelOdometry(v);
          }));
      spdlog::info("republishing {} as {}", bus::topics::kWheelOdometry.name, bus::topics::kOdometryVelocity.name);
    } else {
      subscriptions.push_back(
          context_.Subscribe<msg::Image>(bus::topics::kCameraImage, [weak](const msg::Image& image) {
            if (auto impl = weak.lock()) impl->OnImage(image);
          }));
    }
  }

  void Stop() {
    std::lock_guard lock(mutex_);
    stopped_ = true;
  }

 private:
  void OnWheelOdometry(const msg::Velocity& v) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (!std::isfinite(v.vtrans_mps) || !std::isfinite(v.vrot_radps) || !std::isfinite(v.dt_s))
      return context_.Reject("non_finite_wheel_odometry", "wheel odometry with a non-finite number");
    if (v.dt_s < 0) return context_.Reject("negative_dt", "wheel odometry with dt " + std::to_string(v.dt_s));
    Publish(v);
    context_.SetLastFrame(v.header.frame_seq, v.header.stamp_ns);
  }

  // A reliable reader blocked beyond the preset's limit makes Publish throw: that reader misses
  // this velocity (counted, logged once); the service goes on.
  void Publish(const msg::Velocity& v) {
    try {
      publisher_->Publish(v);
    } catch (const bus::BusError& e) {
      context_.Reject("velocity_not_delivered", e.what());
    }
  }

  void OnImage(const msg::Image& image) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    const std::string problem = camera::ImageMessageProblem(image, static_cast<uint64_t>(config_.max_pixels));
    if (!problem.empty()) return context_.Reject("malformed_image", problem);
    // Frame 0 is a camera's first frame: a restarted camera begins a new run, whose stamps may
    // start below the old run's (a replayed recording).
    const bool new_camera_run = image.header.frame_seq == 0;
    if (previous_stamp_ns_ && !new_camera_run && image.header.stamp_ns <= *previous_stamp_ns_)
      return context_.Reject("stamp_not_increasing", "frame " + std::to_string(image.header.frame_seq) + " stamp " +
                                                         std::to_string(image.header.stamp_ns) + " ns is not after " +
                                                         std::to_string(*previous_stamp_ns_) + " ns");
    const cv::Mat grey = camera::GreyImage(image);
    bool restart = !previous_stamp_ns_ || new_camera_run;
    double dt_s = 0.0;
    if (previous_stamp_ns_) {
      dt_s = static_cast<double>(image.header.stamp_ns - *previous_stamp_ns_) * 1e-9;
      if (grey.size() != previous_size_) {
        spdlog::info("image size changed from {}x{} to {}x{}: restarting the visual odometry", previous_size_.width,
                     previous_size_.height, grey.cols, grey.rows);
        restart = true;
      } else if (dt_s > config_.max_frame_gap_s) {
        context_.Reject("frame_gap", std::to_string(dt_s) + " s since the previous frame (max_frame_gap_s " +
                                         std::to_string(config_.max_frame_gap_s) + "): restarting the visual odometry");
        restart = true;
      }
    }
    if (restart) {
      odometry_.Reset();
      if (floor_) floor_->Reset();
      dt_s = 0.0;
    }
    Velocity velocity;
    std::optional<double> wall_direction;
    try {
      // The first frame's dt is ignored by the odometry but must be valid.
      velocity = odometry_.Update(grey, restart ? 1.0 / config_.visual.camera_hz : dt_s);
      if (floor_) wall_direction = FloorMotion(image, dt_s, velocity);
    } catch (const std::invalid_argument& e) {
      odometry_.Reset();
      if (floor_) floor_->Reset();
      previous_stamp_ns_.reset();
      return context_.Reject("unusable_image", e.what());
    }
    previous_stamp_ns_ = image.header.stamp_ns;
    previous_size_ = grey.size();

    msg::Velocity out;
    out.header = image.header;
    out.vtrans_mps = velocity.vtrans;
    out.vrot_radps = velocity.vrot;
    out.dt_s = dt_s;
    out.source = msg::VelocitySource::VELOCITY_VISUAL;
    if (wall_direction) {
      out.wall_seen = true;
      out.wall_direction_rad = *wall_direction;
    }
    if (floor_) {
      out.boundary_measured = true;
      out.boundary.reserve(boundary_points_.size());
      for (const Eigen::Vector2d& p : boundary_points_)
        out.boundary.push_back({static_cast<float>(p.x()), static_cast<float>(p.y())});
    }
    Publish(out);
    context_.SetLastFrame(image.header.frame_seq, image.header.stamp_ns);
  }

  // Replaces the column-profile velocity by the floor-boundary registration's, seeded with it;
  // a frame that cannot be registered keeps the profiles' turn and the floor odometry's
  // constant-velocity step, a turn on the spot (with turns_from_profiles) the profiles' motion
  // (the registration still sees it, to keep its key frame). Returns the frame's wall direction
  // (wall_direction.h), found in the same boundary. Throws std::invalid_argument for an
  // image the boundary pipeline cannot read (not bgr8, or not the configured camera's size).
  std::optional<double> FloorMotion(const msg::Image& image, double dt_s, Velocity& velocity) {
    if (image.encoding != camera::kBgr8)
      throw std::invalid_argument("floor_odometry needs bgr8 images, got " + image.encoding);
    const occupancy::RadialObstacleProfile profile = boundary_->ProfileFromImage(camera::ImageView(image));
    profile.ObstaclePoints(boundary_points_);
    PlanarMotion prior;
    prior.dx = velocity.vtrans * dt_s;
    prior.dtheta = velocity.vrot * dt_s;
    const double moving_difference = config_.floor.moving_difference;
    const PlanarMotion motion = floor_->Update(
        boundary_points_, prior, moving_difference > 0 && velocity.speed_difference > moving_difference);
    const std::optional<double> wall_direction = WallDirection(boundary_points_, config_.floor.wall_direction);
    if (dt_s <= 0) return wall_direction;
    const double turn_in_place = config_.visual.turn_in_place_vrot_radps;
    if (!(config_.floor.turns_from_profiles && turn_in_place > 0 && std::abs(velocity.vrot) >= turn_in_place)) {
      // Unregistered, the floor odometry returns the prior with its constant-velocity forward step.
      velocity.vtrans = motion.dx / dt_s;
      if (motion.measured) velocity.vrot = motion.dtheta / dt_s;
    }
    return wall_direction;
  }

  ServiceContext& context_;
  const Config config_;
  std::mutex mutex_;
  bool stopped_ = false;
  VisualOdometry odometry_;
  std::unique_ptr<occupancy::ObstacleProfilePipeline> boundary_;  // floor odometry only
  std::unique_ptr<FloorOdometry> floor_;
  std::vector<Eigen::Vector2d> boundary_points_;
  std::optional<int64_t> previous_stamp_ns_;
  cv::Size previous_size_;
  std::shared_ptr<bus::Publisher<msg::Velocity>> publisher_;
};

OdometryNode::OdometryNode(ServiceContext& context, const Config& config)
    : impl_(std::make_shared<Impl>(context, config)) {
  impl_->Start(impl_, subscriptions_);
}

OdometryNode::~OdometryNode() {
  subscriptions_.clear();  // joins the callback thread
  impl_->Stop();
}

}  // namespace rslam::odometry
