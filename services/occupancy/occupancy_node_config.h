#pragma once
// Configuration of the occupancy service (YAML section `occupancy`). The obstacle-profile
// pipeline's keys sit at the top of the section (camera, floor, profile, floor_colour_bgr,
// correct_images), so a library config and a service config read alike.
//
// The defaults are those of the simulator (tools/sim/sim_config.h): a 320x240 camera with a
// 60-degree horizontal field of view, 0.3 m above the floor, tilted down 0.3 rad, and the
// simulator's floor colour, so the demo works with one config file for every process. At that
// height the floor is seen from 0.35 m to the horizon; one pixel is about 3 cm at 1.5 m, which
// is where ranges stop being trusted (reliable_range_m).

#include <cmath>
#include <string>

#include "common/config/config_error.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/occupancy/occupancy_grid.h"
#include "services/occupancy/profile_alignment.h"

namespace rslam::occupancy {

inline ObstacleProfileConfig SimulatorMatchedPipelineConfig() {
  ObstacleProfileConfig c;
  c.camera.width = 320;
  c.camera.height = 240;
  c.camera.fx = c.camera.fy = 160.0 / std::tan(30.0 * M_PI / 180.0);  // (W/2) / tan(hfov/2)
  c.camera.cx = (320 - 1) / 2.0;
  c.camera.cy = (240 - 1) / 2.0;
  c.camera.height_m = 0.3;
  c.camera.tilt_rad = 0.3;
  c.camera.forward_offset_m = 0.0;
  c.floor_colour_bgr = {70, 110, 150};
  c.profile.scan_range_m = 2.0;
  c.profile.range_step_m = 0.01;
  return c;
}

inline GridConfig SimulatorMatchedGridConfig() {
  GridConfig g;
  g.resolution_m = 0.05;
  g.width = 800;  // 40 m x 40 m around the map origin (the robot's first pose)
  g.height = 800;
  g.origin_x_m = -20.0;
  g.origin_y_m = -20.0;
  return g;
}

inline SensorModelConfig SimulatorMatchedSensorConfig() {
  SensorModelConfig s;
  s.reliable_range_m = 1.5;
  return s;
}

struct OccupancyNodeConfig {
  ObstacleProfileConfig pipeline = SimulatorMatchedPipelineConfig();
  GridConfig grid = SimulatorMatchedGridConfig();
  SensorModelConfig sensor = SimulatorMatchedSensorConfig();
  int grid_publish_every_n_frames = 10;
  int join_buffer_frames = 30;          // images / poses waiting for their partner, per side
  double rebuild_min_shift_m = 0.005;   // experience moves smaller than this do not rebuild
  double rebuild_min_turn_rad = 0.002;
  int rebuild_at_most_every_n_frames = 10;  // a rebuild replays every profile: bound how often
  // ... and how much of the time the rebuild thread takes: a rebuild of T seconds is followed by
  // none for T (1 / share - 1) seconds (1: back to back). Rebuilds grow with the map; back to back,
  // late in a long demo run, they kept the service at a full core of a 2-core machine.
  double rebuild_max_busy_share = 0.5;
  double profile_min_spacing_m = 0.0;  // a frame's profile joins the map only this far from the last
  double profile_min_turn_rad = 0.0;   // ... or turned this much (anchored_profile_map.h IsNewView)
  ProfileAlignmentConfig profile_alignment;  // a misplaced profile is moved onto the grid (off by default)
  bool export_maps_on_shutdown = true;  // grid.pgm, grid.yaml, occupancy.png in the state dir

  template <class V>
  void VisitFields(V& v) {
    pipeline.VisitFields(v);
    v("grid", grid, "occupancy grid geometry (map frame)");
    v("sensor", sensor, "range sensor model of the grid update");
    v("grid_publish_every_n_frames", grid_publish_every_n_frames,
      "publish occupancy/grid after this many processed frames (and after every rebuild)");
    v("join_buffer_frames", join_buffer_frames,
      "images and poses kept waiting for their partner frame, per topic");
    v("rebuild_min_shift_m", rebuild_min_shift_m,
      "a corrected map rebuilds the grid only if an experience moved at least this far (m)");
    v("rebuild_min_turn_rad", rebuild_min_turn_rad, "... or turned at least this much (rad)");
    v("rebuild_at_most_every_n_frames", rebuild_at_most_every_n_frames,
      "while the map keeps correcting, rebuild the grid at most once every this many frames");
    v("rebuild_max_busy_share", rebuild_max_busy_share,
      "... and spend at most this share of the time rebuilding (0-1; 1: rebuilds back to back)");
    v("profile_min_spacing_m", profile_min_spacing_m,
      "a frame's profile joins the map only if the robot moved this far from the last one's pose (m) ...");
    v("profile_min_turn_rad", profile_min_turn_rad, "... or turned this much (rad), or the experience changed");
    v("profile_alignment", profile_alignment,
      "a profile drawn where the grid has seen free floor is moved onto the grid's obstacles (profile_alignment.h)");
    v("export_maps_on_shutdown", export_maps_on_shutdown,
      "write grid.pgm, grid.yaml and occupancy.png into the state dir on shutdown");
  }

  void Validate() const {
    pipeline.Validate();  // keys of the pipeline are at the top of the section already
    ValidateNested(grid, "grid");
    ValidateNested(sensor, "sensor");
    ValidateNested(profile_alignment, "profile_alignment");
    Require(grid_publish_every_n_frames >= 1, "grid_publish_every_n_frames", "must be >= 1");
    Require(join_buffer_frames >= 1 && join_buffer_frames <= 10000, "join_buffer_frames", "must be 1..10000");
    Require(rebuild_at_most_every_n_frames >= 0, "rebuild_at_most_every_n_frames", "must be >= 0");
    Require(rebuild_max_busy_share > 0 && rebuild_max_busy_share <= 1, "rebuild_max_busy_share", "must be in (0, 1]");
    Require(std::isfinite(rebuild_min_shift_m) && rebuild_min_shift_m >= 0, "rebuild_min_shift_m",
            "must be >= 0");
    Require(std::isfinite(rebuild_min_turn_rad) && rebuild_min_turn_rad >= 0, "rebuild_min_turn_rad",
            "must be >= 0");
    Require(std::isfinite(profile_min_spacing_m) && profile_min_spacing_m >= 0, "profile_min_spacing_m",
            "must be >= 0");
    Require(std::isfinite(profile_min_turn_rad) && profile_min_turn_rad >= 0, "profile_min_turn_rad",
            "must be >= 0");
  }
};

}  // namespace rslam::occupancy
