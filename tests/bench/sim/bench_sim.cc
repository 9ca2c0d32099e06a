// Frames per second of the simulator's camera renderer on the default world (uwb-room), and the
// cost of one ray cast and one motion step. Poses sweep a pirouette plus a walk so ray lengths
// are typical of the room.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "tools/sim/camera_renderer.h"
#include "tools/sim/robot_motion.h"
#include "tools/sim/world_map.h"

namespace rslam::sim {
namespace {

const WorldMap& World() {
  static const WorldMap world = WorldMap::LoadFromYaml(std::string(RSLAM_SOURCE_DIR) + "/deploy/worlds/uwb-room.yaml");
  return world;
}

void RenderFrames(benchmark::State& state, CameraConfig cam) {
  SceneConfig scene;
  CameraRenderer renderer(World(), scene, cam);
  cv::Mat image;
  const Pose2D start = World().DefaultStartPose();
  int64_t i = 0;
  for (auto _ : state) {
    const double walk = 0.02 * static_cast<double>(i % 100);
    renderer.Render(Pose2D{start.x - 1.0 + walk, start.y, 0.13 * static_cast<double>(i)}, i, image);
    benchmark::DoNotOptimize(image.data);
    ++i;
  }
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Render320x240(benchmark::State& state) {
  CameraConfig cam;
  cam.width = 320;
  cam.height = 240;
  RenderFrames(state, cam);
}
BENCHMARK(BM_Render320x240)->Unit(benchmark::kMicrosecond);

void BM_Render640x480(benchmark::State& state) {
  CameraConfig cam;
  cam.width = 640;
  cam.height = 480;
  RenderFrames(state, cam);
}
BENCHMARK(BM_Render640x480)->Unit(benchmark::kMicrosecond);

void BM_Render640x480NoNoise(benchmark::State& state) {
  CameraConfig cam;
  cam.width = 640;
  cam.height = 480;
  cam.noise_amplitude = 0;
  RenderFrames(state, cam);
}
BENCHMARK(BM_Render640x480NoNoise)->Unit(benchmark::kMicrosecond);

void BM_RenderPanorama360x80(benchmark::State& state) {
  CameraConfig cam;
  cam.panoramic = true;
  cam.width = 360;
  cam.height = 80;
  cam.tilt_rad = 0.0;
  cam.dead_zone_width_rad = 0.6;
  RenderFrames(state, cam);
}
BENCHMARK(BM_RenderPanorama360x80)->Unit(benchmark::kMicrosecond);

void BM_CastRay(benchmark::State& state) {
  const WorldMap& world = World();
  const Pose2D start = world.DefaultStartPose();
  double angle = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(world.CastRay(Eigen::Vector2d(start.x, start.y), angle).distance);
    angle += 0.0137;
  }
}
BENCHMARK(BM_CastRay);

void BM_MotionStepMove(benchmark::State& state) {
  const WorldMap& world = World();
  MotionConfig config;
  RobotMotion motion(world, config, world.DefaultStartPose());
  for (auto _ : state) {
    // Back and forth: 0.5 m out, turn around, 0.5 m back.
    if (!motion.busy()) motion.Command(MotionCommand::Move(0.5));
    const StepResult r = motion.Step();
    if (r.command_finished && r.distance_m != 0.0) motion.Command(MotionCommand::Rotate(M_PI));
    benchmark::DoNotOptimize(r.pose.x);
  }
}
BENCHMARK(BM_MotionStepMove);

}  // namespace
}  // namespace rslam::sim
