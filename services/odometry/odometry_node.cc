#include "services/odometry/odometry_node.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "services/camera/image_message.h"
#include "services/odometry/camera_odometry.h"

namespace rslam::odometry {

class OdometryNode::Impl {
 public:
  Impl(ServiceContext& context, const Config& config)
      : context_(context), config_(config), odometry_(config.visual, config.floor) {}

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
    const cv::Mat view = camera::ImageView(image);
    bool restart = !previous_stamp_ns_ || new_camera_run;
    double dt_s = 0.0;
    if (previous_stamp_ns_) {
      dt_s = static_cast<double>(image.header.stamp_ns - *previous_stamp_ns_) * 1e-9;
      if (view.size() != previous_size_) {
        spdlog::info("image size changed from {}x{} to {}x{}: restarting the visual odometry", previous_size_.width,
                     previous_size_.height, view.cols, view.rows);
        restart = true;
      } else if (dt_s > config_.max_frame_gap_s) {
        context_.Reject("frame_gap", std::to_string(dt_s) + " s since the previous frame (max_frame_gap_s " +
                                         std::to_string(config_.max_frame_gap_s) + "): restarting the visual odometry");
        restart = true;
      }
    }
    if (restart) dt_s = 0.0;
    try {
      odometry_.Update(view, dt_s);
    } catch (const std::invalid_argument& e) {
      odometry_.Reset();
      previous_stamp_ns_.reset();
      return context_.Reject("unusable_image", e.what());
    }
    previous_stamp_ns_ = image.header.stamp_ns;
    previous_size_ = view.size();

    msg::Velocity out = odometry_.Message(dt_s);
    out.header = image.header;
    Publish(out);
    context_.SetLastFrame(image.header.frame_seq, image.header.stamp_ns);
  }

  ServiceContext& context_;
  const Config config_;
  std::mutex mutex_;
  bool stopped_ = false;
  CameraOdometry odometry_;
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
