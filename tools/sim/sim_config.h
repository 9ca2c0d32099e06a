#pragma once
// Configuration of the simulator: the scene (walls, colours), the camera, the robot's motion and
// its wheel odometry. Plain structs in the project's config convention (defaults beside the
// fields, VisitFields for YAML and --help, Validate naming the bad key).

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/config/config_error.h"

namespace rslam::sim {

namespace config_detail {
inline bool IsBgr(const std::vector<int>& c) {
  if (c.size() != 3) return false;
  for (int v : c) {
    if (v < 0 || v > 255) return false;
  }
  return true;
}
}  // namespace config_detail

// How the occupancy map is turned into a 3-D scene.
struct SceneConfig {
  double wall_height_m = 2.0;  // a room: tall enough that near walls fill the upper image
  // The floor is ONE uniform colour so a floor segmenter seeded on it is exact (paper 003).
  std::vector<int> floor_bgr = {70, 110, 150};
  std::vector<int> ceiling_bgr = {235, 225, 215};
  // Walls are textured in panels of this width; each panel's pattern is a hash of its world
  // position, so places differ and a place looks the same on a return.
  double texture_panel_m = 0.6;
  uint32_t texture_seed = 1;

  template <class V>
  void VisitFields(V& v) {
    v("wall_height_m", wall_height_m, "height of the walls extruded from occupied/unknown cells (m)");
    v("floor_bgr", floor_bgr, "uniform floor colour, [B, G, R] 0-255");
    v("ceiling_bgr", ceiling_bgr, "uniform colour above the walls, [B, G, R] 0-255");
    v("texture_panel_m", texture_panel_m, "width of one wall texture panel (m)");
    v("texture_seed", texture_seed, "seed of the wall texture patterns");
  }
  void Validate() const {
    Require(std::isfinite(wall_height_m) && wall_height_m > 0 && wall_height_m <= 100,
            "wall_height_m", "must be in (0, 100]");
    Require(config_detail::IsBgr(floor_bgr), "floor_bgr", "must be 3 integers in 0-255");
    Require(config_detail::IsBgr(ceiling_bgr), "ceiling_bgr", "must be 3 integers in 0-255");
    Require(floor_bgr != ceiling_bgr, "ceiling_bgr", "must differ from floor_bgr");
    Require(std::isfinite(texture_panel_m) && texture_panel_m > 0.01 && texture_panel_m <= 100,
            "texture_panel_m", "must be in (0.01, 100]");
  }
};

// A pinhole camera on the robot (or a 360-degree cylindrical panorama).
struct CameraConfig {
  int width = 320;
  int height = 240;
  double horizontal_fov_rad = 60.0 * M_PI / 180.0;  // paper 003's camera: 60 degrees
  double height_m = 0.3;                             // optical centre above the floor
  double tilt_rad = 0.3;                             // down positive (paper 003 tilts down)
  double forward_offset_m = 0.0;                     // camera ahead of the robot's centre
  // Panoramic mode (paper 001 local view): columns cover 360 degrees, the centre column looking
  // straight ahead and azimuth decreasing to the right as in a forward camera (the left edge looks
  // behind); rows cover vertical_fov_rad around the tilted horizon; columns whose azimuth is inside
  // the dead zone are black.
  bool panoramic = false;
  double vertical_fov_rad = 40.0 * M_PI / 180.0;  // panoramic mode only
  double dead_zone_center_rad = M_PI;              // panoramic mode only (behind the robot)
  double dead_zone_width_rad = 0.0;                // panoramic mode only; 0 = no dead zone
  // Azimuth rays cast per image column (pinhole mode); more rays = exact texture per pixel under
  // tilt, fewer = faster.
  double rays_per_column = 1.5;
  // Deterministic per-frame pixel noise, uniform in [-noise_amplitude, noise_amplitude] grey
  // levels, on walls and ceiling; the floor stays exact unless noise_on_floor.
  int noise_amplitude = 2;
  bool noise_on_floor = false;
  uint32_t noise_seed = 7;

  template <class V>
  void VisitFields(V& v) {
    v("width", width, "image width (px)");
    v("height", height, "image height (px)");
    v("horizontal_fov_rad", horizontal_fov_rad, "horizontal field of view (rad); pinhole mode");
    v("height_m", height_m, "camera height above the floor (m)");
    v("tilt_rad", tilt_rad, "camera tilt (rad, down positive)");
    v("forward_offset_m", forward_offset_m, "camera ahead of the robot's centre of rotation (m)");
    v("panoramic", panoramic, "render a 360-degree cylindrical panorama instead of a pinhole image");
    v("vertical_fov_rad", vertical_fov_rad, "vertical field of view of the panorama (rad)");
    v("dead_zone_center_rad", dead_zone_center_rad, "azimuth of the panorama's masked dead zone (rad)");
    v("dead_zone_width_rad", dead_zone_width_rad, "width of the panorama's dead zone (rad), 0 = none");
    v("rays_per_column", rays_per_column, "azimuth rays cast per image column (pinhole mode)");
    v("noise_amplitude", noise_amplitude, "per-pixel noise amplitude (grey levels), 0 = none");
    v("noise_on_floor", noise_on_floor, "also add noise on the floor (breaks exact floor colour)");
    v("noise_seed", noise_seed, "seed of the pixel noise");
  }
  void Validate() const {
    Require(width >= 4 && width <= 8192, "width", "must be in [4, 8192]");
    Require(height >= 4 && height <= 8192, "height", "must be in [4, 8192]");
    Require(std::isfinite(horizontal_fov_rad) && horizontal_fov_rad > 0.01 &&
                horizontal_fov_rad < M_PI * 170.0 / 180.0,
            "horizontal_fov_rad", "must be in (0.01, 170 degrees)");
    Require(std::isfinite(height_m) && height_m > 0 && height_m < 100, "height_m", "must be in (0, 100)");
    Require(std::isfinite(tilt_rad) && std::abs(tilt_rad) < M_PI / 2 - 0.05, "tilt_rad",
            "must be within +-(90 - 3) degrees");
    Require(std::isfinite(forward_offset_m) && std::abs(forward_offset_m) < 10, "forward_offset_m",
            "must be within +-10 m");
    Require(std::isfinite(vertical_fov_rad) && vertical_fov_rad > 0.01 &&
                vertical_fov_rad < M_PI * 170.0 / 180.0,
            "vertical_fov_rad", "must be in (0.01, 170 degrees)");
    Require(std::isfinite(dead_zone_center_rad), "dead_zone_center_rad", "must be finite");
    Require(std::isfinite(dead_zone_width_rad) && dead_zone_width_rad >= 0 &&
                dead_zone_width_rad < 2 * M_PI,
            "dead_zone_width_rad", "must be in [0, 2 pi)");
    Require(std::isfinite(rays_per_column) && rays_per_column >= 0.25 && rays_per_column <= 16,
            "rays_per_column", "must be in [0.25, 16]");
    // Wall texels differ from the floor colour by 20 levels per channel: noise must stay below.
    Require(noise_amplitude >= 0 && noise_amplitude <= 16, "noise_amplitude", "must be in [0, 16]");
  }
};

// Piece-wise linear motion: turns on the spot and straight moves (paper 003).
struct MotionConfig {
  double time_step_s = 0.1;        // one camera frame at 10 Hz
  double linear_speed_mps = 0.25;
  double angular_speed_radps = 0.8;
  double robot_radius_m = 0.18;
  int pirouette_turns = 12;
  double pirouette_turn_rad = 30.0 * M_PI / 180.0;
  double pirouette_pause_s = 0.2;  // standing still after each turn so frames are taken

  template <class V>
  void VisitFields(V& v) {
    v("time_step_s", time_step_s, "simulation time step (s), one camera frame");
    v("linear_speed_mps", linear_speed_mps, "speed of straight moves (m/s)");
    v("angular_speed_radps", angular_speed_radps, "speed of turns on the spot (rad/s)");
    v("robot_radius_m", robot_radius_m, "robot radius for collision checks (m)");
    v("pirouette_turns", pirouette_turns, "turns in one pirouette");
    v("pirouette_turn_rad", pirouette_turn_rad, "angle of each pirouette turn (rad)");
    v("pirouette_pause_s", pirouette_pause_s, "pause after each pirouette turn (s)");
  }
  void Validate() const {
    Require(std::isfinite(time_step_s) && time_step_s > 0 && time_step_s <= 10, "time_step_s",
            "must be in (0, 10]");
    Require(std::isfinite(linear_speed_mps) && linear_speed_mps > 0 && linear_speed_mps <= 10,
            "linear_speed_mps", "must be in (0, 10]");
    Require(std::isfinite(angular_speed_radps) && angular_speed_radps > 0 && angular_speed_radps <= 20,
            "angular_speed_radps", "must be in (0, 20]");
    Require(std::isfinite(robot_radius_m) && robot_radius_m >= 0 && robot_radius_m <= 10,
            "robot_radius_m", "must be in [0, 10]");
    Require(pirouette_turns >= 1 && pirouette_turns <= 360, "pirouette_turns", "must be in [1, 360]");
    Require(std::isfinite(pirouette_turn_rad) && pirouette_turn_rad > 0 && pirouette_turn_rad <= 2 * M_PI,
            "pirouette_turn_rad", "must be in (0, 2 pi]");
    Require(std::isfinite(pirouette_pause_s) && pirouette_pause_s >= 0 && pirouette_pause_s <= 60,
            "pirouette_pause_s", "must be in [0, 60]");
  }
};

// Wheel odometry noise: Gaussian, standard deviation proportional to the true motion.
struct WheelOdometryConfig {
  double translation_noise_per_m = 0.05;    // sigma of distance, per metre travelled
  double rotation_noise_per_rad = 0.05;     // sigma of rotation, per radian turned
  double rotation_noise_per_m = 0.02;       // sigma of rotation (rad), per metre travelled
  uint32_t seed = 11;

  template <class V>
  void VisitFields(V& v) {
    v("translation_noise_per_m", translation_noise_per_m, "distance noise sigma per metre travelled");
    v("rotation_noise_per_rad", rotation_noise_per_rad, "rotation noise sigma per radian turned");
    v("rotation_noise_per_m", rotation_noise_per_m, "rotation noise sigma (rad) per metre travelled");
    v("seed", seed, "seed of the odometry noise");
  }
  void Validate() const {
    Require(std::isfinite(translation_noise_per_m) && translation_noise_per_m >= 0 && translation_noise_per_m <= 1,
            "translation_noise_per_m", "must be in [0, 1]");
    Require(std::isfinite(rotation_noise_per_rad) && rotation_noise_per_rad >= 0 && rotation_noise_per_rad <= 1,
            "rotation_noise_per_rad", "must be in [0, 1]");
    Require(std::isfinite(rotation_noise_per_m) && rotation_noise_per_m >= 0 && rotation_noise_per_m <= 1,
            "rotation_noise_per_m", "must be in [0, 1]");
  }
};

// Everything the simulator process needs.
struct SimConfig {
  std::string world_yaml = "deploy/worlds/uwb-room.yaml";
  SceneConfig scene;
  CameraConfig camera;
  MotionConfig motion;
  WheelOdometryConfig wheel_odometry;

  template <class V>
  void VisitFields(V& v) {
    v("world_yaml", world_yaml, "ROS map_server YAML of the world (relative to the repo root or absolute)");
    v("scene", scene, "walls and colours");
    v("camera", camera, "the simulated camera");
    v("motion", motion, "robot motion");
    v("wheel_odometry", wheel_odometry, "wheel odometry noise");
  }
  void Validate() const {
    Require(!world_yaml.empty(), "world_yaml", "must name a file");
    ValidateNested(scene, "scene");
    ValidateNested(camera, "camera");
    ValidateNested(motion, "motion");
    ValidateNested(wheel_odometry, "wheel_odometry");
  }
};

}  // namespace rslam::sim
