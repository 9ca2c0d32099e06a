// System tests: the RatSLAM services as separate processes build exactly the map of the
// in-process runner (`rslam run`), whatever the camera's pace, with services on either DDS
// vendor, and again from a recording of the run played into fresh services.
//
// Frames: a generated loop (loop_frames.h, 36 places per lap, 2 laps + 8 frames = 80 frames of
// 160x120) that learns templates and closes the loop; the config is synthetic_loop_160x120.yaml.
// Every run is on its own TestDomain; every child process is ended with the test.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "services/camera/frame_source.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"
#include "tests/system/services/loop_frames.h"
#include "tests/system/services/map_comparison.h"
#include "tests/system/services/service_pipeline.h"
#include "tools/run/ratslam_config.h"
#include "tools/run/ratslam_runner.h"

namespace rslam::system_test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

const std::string kConfig = RSLAM_SOURCE_DIR "/tests/system/services/synthetic_loop_160x120.yaml";
constexpr int kPlacesPerLap = 36;
constexpr int kFrames = 2 * kPlacesPerLap + 8;
constexpr double kFps = 10.0;
// Positions must agree to this (they are expected to be bit-identical: same code, same inputs,
// same order of floating-point operations; the tolerance only makes a difference readable).
constexpr double kTolerance = 1e-9;

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// "frames 12, 79 have no pose" for a failure message.
std::string MissingPoses(const std::vector<msg::ExperiencePose>& poses, int frames) {
  std::vector<bool> seen(static_cast<std::size_t>(frames), false);
  for (const auto& pose : poses)
    if (pose.header.frame_seq < seen.size()) seen[pose.header.frame_seq] = true;
  std::string missing;
  for (int i = 0; i < frames; ++i)
    if (!seen[static_cast<std::size_t>(i)]) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
  return missing.empty() ? "" : "frames " + missing + " have no pose";
}

// What the experience map looked like after each frame.
struct FrameState {
  uint32_t current_experience_id = 0;
  uint32_t experience_count = 0;
  uint32_t link_count = 0;
  double experience_x_m = 0, experience_y_m = 0, experience_theta_rad = 0;
};

struct RunnerResult {
  MapRecord map;
  std::vector<FrameState> frames;
  uint64_t loop_closures = 0;
  std::size_t templates = 0;
};

// `rslam run` in process: the same frame source as the camera service, its stamps.
RunnerResult RunInProcess(const std::string& config_file, const std::string& folder, double fps) {
  run::RatSlamRunner runner(run::RatSlamConfigFromYaml(YAML::LoadFile(config_file)));
  auto source = camera::OpenImageSequence(folder, fps);
  RunnerResult result;
  while (auto frame = source->Next()) {
    runner.ProcessFrame(frame->image, frame->stamp_ns);
    const auto& map = runner.experience_map();
    FrameState state;
    state.current_experience_id = map.current_id();
    state.experience_count = static_cast<uint32_t>(map.experiences().size());
    state.link_count = static_cast<uint32_t>(map.links().size());
    const auto& current = map.experiences().at(map.current_id());
    state.experience_x_m = current.x_m;
    state.experience_y_m = current.y_m;
    state.experience_theta_rad = current.th_rad;
    result.frames.push_back(state);
  }
  result.map = MapOfRunner(runner);
  result.loop_closures = runner.loop_closures();
  result.templates = runner.templates().size();
  return result;
}

struct ServiceRun {
  std::vector<msg::ExperiencePose> poses;
  msg::ExperienceMap map;
  double seconds = 0;
};

// The first frame whose published pose disagrees with the runner's state after that frame.
std::string FirstFrameDrift(const RunnerResult& expected, const std::vector<msg::ExperiencePose>& poses) {
  for (std::size_t i = 0; i < std::min(poses.size(), expected.frames.size()); ++i) {
    const auto& e = expected.frames[i];
    const auto& p = poses[i];
    if (p.header.frame_seq != i || p.current_experience_id != e.current_experience_id ||
        p.experience_count != e.experience_count || p.link_count != e.link_count ||
        !(std::abs(p.experience_x_m - e.experience_x_m) <= kTolerance) ||
        !(std::abs(p.experience_y_m - e.experience_y_m) <= kTolerance) ||
        !(std::abs(p.experience_theta_rad - e.experience_theta_rad) <= kTolerance)) {
      std::ostringstream out;
      out.precision(17);
      out << "first drift at pose " << i << " (frame_seq " << p.header.frame_seq << ", action_seq " << p.action_seq
          << "): runner current " << e.current_experience_id << " of " << e.experience_count << " experiences, "
          << e.link_count << " links, at (" << e.experience_x_m << ", " << e.experience_y_m << ", "
          << e.experience_theta_rad << "); service current " << p.current_experience_id << " of "
          << p.experience_count << ", " << p.link_count << " links, at (" << p.experience_x_m << ", "
          << p.experience_y_m << ", " << p.experience_theta_rad << ")";
      return out.str();
    }
  }
  return "";
}

class ServicesMapTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    frames_ = std::make_unique<testing::ScratchFolder>("rslam-system-frames");
    WriteLoopFrames(frames_->path(), kPlacesPerLap, kFrames);
    const auto start = Clock::now();
    runner_ = std::make_unique<RunnerResult>(RunInProcess(kConfig, frames_->path().string(), kFps));
    std::printf("[ runner ] %d frames in %.3f s: %s, %llu loop closures\n", kFrames, SecondsSince(start),
                Summary(runner_->map).c_str(), static_cast<unsigned long long>(runner_->loop_closures));
  }
  static void TearDownTestSuite() {
    runner_.reset();
    frames_.reset();
  }

  void SetUp() override {
    // The frames must exercise the whole map: templates recognised, a loop closed.
    ASSERT_EQ(runner_->frames.size(), static_cast<std::size_t>(kFrames));
    ASSERT_GE(runner_->loop_closures, 1u) << "the generated loop must close in the runner";
    ASSERT_GT(runner_->map.links.size(), 10u);
  }

  // Starts the services (vendors per service), feeds the camera, collects poses and the final
  // snapshot; the services must stop cleanly.
  void RunServices(const std::map<std::string, std::string>& vendors, double rate_hz, ServiceRun& out,
                   const std::function<void(ServicePipeline&)>& before_camera = {},
                   const std::function<void(ServicePipeline&)>& after_frames = {}, int camera_readers = 2) {
    RunServicesOn(kConfig, frames_->path().string(), kFrames, vendors, rate_hz, out, before_camera, after_frames,
                  camera_readers);
  }

  static void RunServicesOn(const std::string& config, const std::string& images, int frames,
                            const std::map<std::string, std::string>& vendors, double rate_hz, ServiceRun& out,
                            const std::function<void(ServicePipeline&)>& before_camera = {},
                            const std::function<void(ServicePipeline&)>& after_frames = {}, int camera_readers = 2) {
    testing::TestDomain domain;
    testing::ScratchFolder logs("rslam-system-logs");
    const auto start = Clock::now();
    ServicePipeline pipeline(domain.id(), {.config_file = config, .vendors = vendors, .log_dir = logs.path().string()});
    if (before_camera) before_camera(pipeline);
    pipeline.StartCamera({.folder = images, .fps = kFps, .rate_hz = rate_hz, .vendor = {}, .readers = camera_readers});
    ASSERT_TRUE(pipeline.WaitForFrames(frames, 60s))
        << pipeline.Poses().size() << " of " << frames << " poses; " << MissingPoses(pipeline.Poses(), frames) << "\n"
        << pipeline.Logs();
    out.seconds = SecondsSince(start);
    ASSERT_EQ(pipeline.WaitCameraExit(10s), 0) << pipeline.Logs();
    if (after_frames) after_frames(pipeline);
    out.poses = pipeline.Poses();
    out.map = *pipeline.LatestMap();
    const std::string stop_problems = pipeline.StopServices();
    EXPECT_EQ(stop_problems, "");
  }

  // The service run's map equals the runner's, frame by frame and at the end.
  static void ExpectRunnerMap(const ServiceRun& run, const std::string& what) {
    ExpectMapOf(*runner_, run, what);
  }

  static void ExpectMapOf(const RunnerResult& runner, const ServiceRun& run, const std::string& what) {
    const int frames = static_cast<int>(runner.frames.size());
    ASSERT_EQ(run.poses.size(), runner.frames.size()) << what << ": one pose per frame";
    EXPECT_EQ(FirstFrameDrift(runner, run.poses), "") << what;
    EXPECT_EQ(run.map.action_seq, static_cast<uint64_t>(frames - 1)) << what;
    const MapDifference d = CompareMaps(runner.map, MapOfSnapshot(run.map), kTolerance);
    EXPECT_EQ(d.description, "") << what << " vs the runner";
    RecordProperty(what + "_max_abs_difference", std::to_string(d.max_abs_difference));
    std::printf("[ %s ] %d frames in %.2f s: %s; largest difference from the runner %.3g\n", what.c_str(), frames,
                run.seconds, Summary(MapOfSnapshot(run.map)).c_str(), d.max_abs_difference);
  }

  static void ExpectSameMaps(const ServiceRun& a, const ServiceRun& b, const std::string& what) {
    const MapDifference d = CompareMaps(MapOfSnapshot(a.map), MapOfSnapshot(b.map), kTolerance);
    EXPECT_EQ(d.description, "") << what;
    EXPECT_EQ(d.max_abs_difference, 0.0) << what << ": expected bit-identical maps";
  }

  static std::unique_ptr<testing::ScratchFolder> frames_;
  static std::unique_ptr<RunnerResult> runner_;
};

std::unique_ptr<testing::ScratchFolder> ServicesMapTest::frames_;
std::unique_ptr<RunnerResult> ServicesMapTest::runner_;

TEST_F(ServicesMapTest, ServicesBuildTheSameMapAsRslamRun) {
  ServiceRun run;
  ASSERT_NO_FATAL_FAILURE(RunServices({}, 0.0, run));
  ExpectRunnerMap(run, "services, cyclone, camera lockstep");
}

TEST_F(ServicesMapTest, SameMapAtAnyFrameRate) {
  // The frames are stamped at kFps (10 Hz): 1x, 10x and as fast as the services take them.
  ServiceRun as_fast_as_possible, real_time, ten_times;
  ASSERT_NO_FATAL_FAILURE(RunServices({}, 0.0, as_fast_as_possible));
  ASSERT_NO_FATAL_FAILURE(RunServices({}, kFps, real_time));
  ASSERT_NO_FATAL_FAILURE(RunServices({}, 10 * kFps, ten_times));
  ExpectRunnerMap(as_fast_as_possible, "camera as fast as possible");
  ExpectRunnerMap(real_time, "camera at 1x (10 Hz)");
  ExpectRunnerMap(ten_times, "camera at 10x (100 Hz)");
  ExpectSameMaps(as_fast_as_possible, real_time, "1x vs as fast as possible");
  ExpectSameMaps(as_fast_as_possible, ten_times, "10x vs as fast as possible");
}

TEST_F(ServicesMapTest, MixedVendorInteropRunGivesTheSameMap) {
  ServiceRun cyclone, mixed;
  ASSERT_NO_FATAL_FAILURE(RunServices({}, 0.0, cyclone));
  ASSERT_NO_FATAL_FAILURE(RunServices({{"templates", "fastdds"}, {"pose-cells", "fastdds"}}, 0.0, mixed));
  ExpectRunnerMap(mixed, "templates + pose cells on fastdds, the rest cyclone");
  ExpectSameMaps(cyclone, mixed, "mixed vendors vs all cyclone");
}

TEST_F(ServicesMapTest, ReplayedRecordingRebuildsTheSameMap) {
  testing::ScratchFolder folder("rslam-system-record");
  const std::string recording = folder / "run.mcap";
  std::unique_ptr<testing::ChildProcess> recorder;
  ServiceRun original;
  ASSERT_NO_FATAL_FAILURE(RunServices(
      {}, 0.0, original,
      [&](ServicePipeline& pipeline) {
        recorder = std::make_unique<testing::ChildProcess>(
            BinaryDir() + "rslam",
            std::vector<std::string>{"record", "-o", recording, "--domain", std::to_string(pipeline.domain())});
        // The recorder announces each publisher it discovered: the services' topics are up.
        ASSERT_TRUE(testing::WaitFor([&] { return recorder->Output().find("experience_map/pose") != std::string::npos; },
                                     20s))
            << recorder->Tail();
      },
      [&](ServicePipeline&) {
        // The recorder has every message once it acknowledged them; SIGINT closes the file.
        recorder->Signal(SIGINT);
        const auto code = recorder->WaitExit(20s);
        ASSERT_EQ(code, 0) << recorder->Tail();
      },
      /*camera_readers=*/3));
  ExpectRunnerMap(original, "recorded run");
  ASSERT_TRUE(std::filesystem::exists(recording)) << recorder->Tail();

  ServiceRun replayed;
  {
    testing::TestDomain domain;
    testing::ScratchFolder logs("rslam-system-logs");
    const auto start = Clock::now();
    ServicePipeline pipeline(domain.id(), {.config_file = kConfig, .vendors = {}, .log_dir = logs.path().string()});
    testing::ChildProcess player(BinaryDir() + "rslam",
                                 {"play", recording, "--max", "--topics", "camera/image", "--wait-for-readers", "2",
                                  "--domain", std::to_string(domain.id())});
    ASSERT_TRUE(pipeline.WaitForFrames(kFrames, 60s))
        << pipeline.Poses().size() << " of " << kFrames << " poses\n" << player.Tail() << pipeline.Logs();
    replayed.seconds = SecondsSince(start);
    ASSERT_EQ(player.WaitExit(20s), 0) << player.Tail();
    replayed.poses = pipeline.Poses();
    replayed.map = *pipeline.LatestMap();
    EXPECT_EQ(pipeline.StopServices(), "");
  }
  ExpectRunnerMap(replayed, "replayed recording (play --max)");
  ExpectSameMaps(original, replayed, "replayed vs original");
}

// The real iRat sample frames (416x240 colour, 10 of them) looped 10 times, with the iRat
// preset: the same comparison on camera images. Skipped without the shared data.
TEST_F(ServicesMapTest, IratFramesLoopedThroughServicesGiveTheRunnersMap) {
  const std::string data = testing::SharedDataDir();
  if (data.empty() || !std::filesystem::is_directory(data + "/irat")) GTEST_SKIP() << "no shared iRat frames";
  const std::vector<std::string> images = camera::ListImages(data + "/irat");
  ASSERT_FALSE(images.empty());
  testing::ScratchFolder folder("rslam-system-irat");
  const std::string list = folder / "frames.txt";
  int frames = 0;
  {
    std::ofstream out(list);
    for (int lap = 0; lap < 10; ++lap)
      for (const auto& image : images) {
        out << image << "\n";
        ++frames;
      }
  }
  const std::string preset = RSLAM_SOURCE_DIR "/deploy/presets/irat.yaml";
  const RunnerResult runner = RunInProcess(preset, list, kFps);
  ASSERT_EQ(runner.frames.size(), static_cast<std::size_t>(frames));
  ServiceRun run;
  ASSERT_NO_FATAL_FAILURE(RunServicesOn(preset, list, frames, {}, 0.0, run));
  ExpectMapOf(runner, run, "iRat frames looped");
}

}  // namespace
}  // namespace rslam::system_test
