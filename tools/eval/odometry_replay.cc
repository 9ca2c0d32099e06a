#include "tools/eval/odometry_replay.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/math/angle.h"
#include "services/odometry/camera_odometry.h"
#include "tools/eval/trajectory_alignment.h"
#include "tools/sim/camera_renderer.h"

namespace rslam::eval {

OdometryReplayResult ReplayOdometry(const sim::WorldMap& world, const sim::SimConfig& sim,
                                    const odometry::OdometryNodeConfig& config, std::span<const ReplayedFrame> frames,
                                    std::vector<msg::Velocity>* messages) {
  if (frames.size() < 2) throw std::invalid_argument("ReplayOdometry: fewer than two frames");
  sim::CameraRenderer renderer(world, sim.scene, sim.camera);
  odometry::CameraOdometry odometry(config.visual, config.floor);
  OdometryReplayResult result;
  std::vector<StampedPose2D> estimate, truth;
  estimate.reserve(frames.size());
  truth.reserve(frames.size());
  cv::Mat image;
  Pose2D pose{0.0, 0.0, 0.0};  // dead reckoning from the first frame
  double heading_error2 = 0.0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const ReplayedFrame& frame = frames[i];
    if (i > 0 && frame.stamp_ns <= frames[i - 1].stamp_ns)
      throw std::invalid_argument("ReplayOdometry: frame " + std::to_string(frame.frame_seq) + "'s stamp does not increase");
    const double dt = i == 0 ? 0.0 : static_cast<double>(frame.stamp_ns - frames[i - 1].stamp_ns) * 1e-9;
    renderer.Render(frame.truth, frame.frame_seq, image);
    const odometry::Velocity& v = odometry.Update(image, dt).velocity;
    if (messages) {
      msg::Velocity& m = messages->emplace_back(odometry.Message(dt));
      m.header.frame_seq = frame.frame_seq;
      m.header.stamp_ns = frame.stamp_ns;
    }
    if (frame.recorded_vtrans_mps && frame.recorded_vrot_radps) {
      ++result.frames_recorded;
      if (std::abs(*frame.recorded_vtrans_mps - v.vtrans) > 1e-9 || std::abs(*frame.recorded_vrot_radps - v.vrot) > 1e-9)
        ++result.frames_differing_from_recorded;
    }
    // As the experience map integrates: forward along the heading, then the turn.
    pose.x += v.vtrans * dt * std::cos(pose.theta);
    pose.y += v.vtrans * dt * std::sin(pose.theta);
    pose.theta += v.vrot * dt;
    if (i > 0) {
      const double true_turn = WrapAngle(frame.truth.theta - frames[i - 1].truth.theta);
      const double turn_error = std::abs(v.vrot * dt - true_turn);
      result.turn_error_sum_rad += turn_error;
      if (turn_error > 0.03) ++(std::abs(true_turn) > 0.01 ? result.turn_frames_misread : result.straight_frames_misread);
    }
    const double heading_error = WrapAngle(pose.theta - (frame.truth.theta - frames[0].truth.theta));
    heading_error2 += heading_error * heading_error;
    estimate.push_back({frame.stamp_ns, pose.x, pose.y, pose.theta});
    truth.push_back({frame.stamp_ns, frame.truth.x, frame.truth.y, frame.truth.theta});
  }
  result.frames = frames.size();
  result.heading_rms_rad = std::sqrt(heading_error2 / static_cast<double>(frames.size()));
  result.final_heading_error_rad =
      WrapAngle(pose.theta - (frames.back().truth.theta - frames.front().truth.theta));
  const TrajectoryError error = AlignAndCompare(estimate, truth, /*with_scale=*/true);
  result.ate_m = error.ate_m;
  result.scale = error.scale;
  return result;
}

}  // namespace rslam::eval
