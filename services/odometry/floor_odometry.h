#pragma once
// Metric visual odometry from the floor boundary: planar motion by registering, frame after frame,
// the points where the floor meets obstacles (a camera-made range scan) against a key frame's.
//
// Why: the perceptual speed of paper 000 (eq. 6) is the image change, not a distance; its scale
// depends on how far and how textured the scene is, so a metric map (the occupancy grid, which
// hangs its range profiles on the experience poses) cannot be built on it. A camera of known
// height and tilt over a flat floor of one colour (paper 003's assumptions) measures ranges: the
// first non-floor pixel above the floor on each bearing, read through the inverse perspective
// map, is the obstacle's base in the robot frame (services/occupancy RadialObstacleProfile).
//
// Each frame's boundary points are registered to the key frame's by point-to-line ICP in the
// plane (x forward, y left, theta counter-clockwise): nearest key point within
// max_pair_distance_m, the line through it and its profile neighbours (no pair where that point
// ends its line: boundary_scan.h), Gauss-Newton on
// (x, y, theta), pairs weighted by 1 / (r_a r_b)^2 (a row's floor footprint grows with r^2), with
// priors that keep the robot from moving sideways and the turn near the prior's. ICP starts from
// up to three seeds (the prior, the previous frame's motion, the last forward step with the
// prior's turn) and keeps the closest fit (unless it pairs up clearly fewer points). The key frame is replaced once the robot has moved keyframe_translation_m or
// turned keyframe_rotation_rad from it, or when a frame cannot be registered, so per-frame pixel
// noise does not accumulate over a straight move: the distance travelled from a key frame is one
// registration, not the sum of many small ones.
//
// The caller's prior says whether the robot moves forward (the column profiles see that well, but
// not how fast): while it does, the forward step seeded into the registration, and returned when a
// frame cannot be registered, is the median of the last coast_speed_steps registered forward steps of
// straight frames the prior calls moving, each after such a frame (constant velocity; one odd
// registration, a turn's step or the camera settling as a turn ends does not set the speed) if
// the newest is at most coast_frames old, else the prior's own.
// A still prior (dx 0) that does not turn, right after moving frames, is taken as moving for up
// to coast_still_frames frames unless a registration measures the robot standing (less than
// half the coasting step): driving straight past a plain wall,
// the column profiles can change less than their noise floor for a frame or two (on a demo path,
// 360 of 3,199 moving frames read dx 0 and were not registered: 8.9 m of 79.7 m lost).
// The caller may say more: camera_moves, the images changing by more than a still camera's noise
// although too little for a speed (odometry_node_config.h moving_difference), makes a still
// prior moving for as long as it lasts, and without it a still prior is still (with
// coast_still_frames 0). Across open floor, with the walls 3 m and more away, the profiles read
// no speed for long stretches; on a recorded demo path 95% of such driving frames changed more
// than 0.00098, 95% of standing frames less than 0.00051.
// A frame is not registered (the seeded prior is returned, measured = false) when
// either frame has fewer than min_points points, too few pairs survive, or the geometry leaves a
// direction unconstrained (a corridor's parallel walls say nothing about motion along them):
// smallest eigenvalue of the normal matrix per pair below min_constraint.
//
// Pure and deterministic; a frame costs a few small allocations (its points, the seeds).

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

#include "common/config/config_error.h"
#include "services/odometry/boundary_scan.h"

namespace rslam::odometry {

struct FloorOdometryConfig {
  double max_range_m = 1.5;             // boundary points farther away are not used
  int min_points = 12;                  // per frame, and pairs after outlier rejection
  double max_pair_distance_m = 0.10;    // a pair farther apart (after the prediction) is an outlier
  double keyframe_translation_m = 0.4;  // new key frame after this much travel from it ...
  double keyframe_rotation_rad = 0.35;  // ... or this much turn
  int iterations = 12;
  double min_constraint = 0.02;         // smallest normal-matrix eigenvalue per pair (see above)
  int coast_frames = 50;                // constant velocity for at most this many frames
  // The coasting speed is the median of this many registered steps: 1.5 s at 10 Hz (on a replayed
  // demo path 5 gave ATE 0.94 m, 15 0.84 m).
  int coast_speed_steps = 15;
  int coast_still_frames = 2;           // still priors right after moving frames taken as moving
  double straight_max_turn_rad = 0.01;  // a frame turning less is a straight move (see above)
  // The robot cannot move sideways: the lateral offset stays the prior's unless the points insist
  // (as if every pair had a lateral normal ten times over). The turn stays near the column
  // profiles' (unbiased, quantised to a pixel; boundary points, quantised to image rows, pull
  // turns short): with the true turn as prior on a recorded demo path, the summed turn came out
  // 0.3% short at 3 (1.7% at 0.1, 0.7% at 1).
  double lateral_prior = 10.0;
  double rotation_prior = 3.0;

  template <class V>
  void VisitFields(V& v) {
    v("max_range_m", max_range_m, "floor-boundary points farther than this are not used (m)");
    v("min_points", min_points, "boundary points (and surviving pairs) needed to register a frame");
    v("max_pair_distance_m", max_pair_distance_m, "point pairs farther apart are outliers (m)");
    v("keyframe_translation_m", keyframe_translation_m, "a new key frame after this much travel (m)");
    v("keyframe_rotation_rad", keyframe_rotation_rad, "... or this much turn (rad)");
    v("iterations", iterations, "ICP iterations per frame");
    v("min_constraint", min_constraint,
      "smallest eigenvalue of the ICP normal matrix per pair; below it the frame is not registered");
    v("coast_frames", coast_frames,
      "while the prior says the robot moves, keep the registered speed for this many frames after the last registration");
    v("coast_speed_steps", coast_speed_steps,
      "the coasting speed is the median of this many registered forward steps of straight moving frames");
    v("coast_still_frames", coast_still_frames,
      "still priors (dx 0) right after moving frames taken as moving, at most this many in a row");
    v("straight_max_turn_rad", straight_max_turn_rad,
      "a frame turning less than this is straight: its registered step sets the coasting speed, a still one may coast (rad)");
    v("lateral_prior", lateral_prior, "weight (per point pair) holding the robot from moving sideways");
    v("rotation_prior", rotation_prior, "weight (per point pair) holding the turn near the prior's");
  }
  void Validate() const {
    Require(max_range_m > 0 && max_range_m < 100, "max_range_m", "must be in (0, 100)");
    Require(min_points >= 3, "min_points", "must be >= 3");
    Require(max_pair_distance_m > 0, "max_pair_distance_m", "must be positive");
    Require(keyframe_translation_m > 0, "keyframe_translation_m", "must be positive");
    Require(keyframe_rotation_rad > 0 && keyframe_rotation_rad < 3.14, "keyframe_rotation_rad", "must be in (0, pi)");
    Require(iterations >= 1 && iterations <= 100, "iterations", "must be 1..100");
    Require(min_constraint >= 0, "min_constraint", "must be >= 0");
    Require(coast_frames >= 0, "coast_frames", "must be >= 0");
    Require(coast_speed_steps >= 1 && coast_speed_steps <= 100000, "coast_speed_steps", "must be 1..100000");
    Require(coast_still_frames >= 0, "coast_still_frames", "must be >= 0");
    Require(straight_max_turn_rad >= 0, "straight_max_turn_rad", "must be >= 0");
    Require(lateral_prior >= 0, "lateral_prior", "must be >= 0");
    Require(rotation_prior >= 0, "rotation_prior", "must be >= 0");
  }
};

// Planar motion from the previous frame's robot pose to this frame's, in the previous frame.
struct PlanarMotion {
  double dx = 0.0;      // m, forward
  double dy = 0.0;      // m, left
  double dtheta = 0.0;  // rad, counter-clockwise
  bool measured = false;  // false: the prior was returned (see the header comment)
  int pairs = 0;          // point pairs of the last ICP iteration
};

class FloorOdometry {
 public:
  explicit FloorOdometry(FloorOdometryConfig config);  // throws ConfigError on a bad config
  FloorOdometry(const FloorOdometry&) = delete;
  FloorOdometry& operator=(const FloorOdometry&) = delete;

  // boundary: this frame's floor-boundary points in the robot frame, in bearing order (points
  // beyond max_range_m are dropped here). prior: the motion expected from other cues (the
  // column-shift rotation, the previous speed); it seeds the registration and is returned when
  // the frame cannot be registered. Non-finite points or prior throw std::invalid_argument.
  // camera_moves: the images change more than a still camera's noise although too little for the
  // prior to read a speed (dx 0): such a frame is taken as moving (see the header comment).
  PlanarMotion Update(std::span<const Eigen::Vector2d> boundary, const PlanarMotion& prior,
                      bool camera_moves = false);

  void Reset();
  const FloorOdometryConfig& config() const { return config_; }

 private:
  void MakeKeyFrame(std::vector<Eigen::Vector2d>&& points);
  // ICP from the predicted pose of the robot in the key frame, priors held at `prior`.
  Alignment Register(std::span<const Eigen::Vector2d> points, const Eigen::Vector3d& predicted,
                     const Eigen::Vector3d& prior) const;

  const FloorOdometryConfig config_;
  bool has_key_ = false;
  BoundaryScan key_;
  Eigen::Vector3d key_to_robot_ = Eigen::Vector3d::Zero();  // robot pose in the key frame (x, y, theta)
  PlanarMotion last_motion_;     // the previous frame's, when it was registered
  bool last_registered_ = false;
  // Keeps a registered forward step and the median of the last coast_speed_steps of them, the
  // coasting step (see the header comment): once per registered step, not every frame.
  void RecordMovingStep(double dx);

  std::vector<double> moving_dx_;     // ring of registered forward steps of moving frames (coast_speed_steps)
  uint64_t moving_dx_count_ = 0;      // how many were registered (all time)
  double coast_step_ = 0.0;           // their median (last coast_speed_steps)
  int frames_since_moving_dx_ = -1;   // since the newest; -1: none yet
  bool was_moving_ = false;  // the previous frame was taken as moving
  int still_run_ = 0;        // still priors in a row taken as moving
};

}  // namespace rslam::odometry
