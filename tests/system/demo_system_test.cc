// The demo end to end, shortened: the simulator and the seven services as processes on the
// test's own domain for about a minute; the results folder must hold every file and a
// summary.json whose figures are present and sane.

#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// `rslam demo` when the command line has it, else the standalone driver.
std::vector<std::string> DemoCommand() {
  const std::string rslam = RSLAM_BINARY_DIR "/bin/rslam";
  // `rslam demo --help` exits 0 even without the subcommand (help wins): look for it in the list.
  if (::access(rslam.c_str(), X_OK) == 0 &&
      std::system(("'" + rslam + "' --help 2>&1 | grep -Eq '^ +demo( |$)'").c_str()) == 0)
    return {rslam, "demo"};
  return {RSLAM_BINARY_DIR "/bin/rslam-demo-driver", "demo"};
}

TEST(DemoSystemTest, ShortDemoWritesEveryResultWithSaneFigures) {
  testing::TestDomain domain;
  char pattern[] = "/tmp/rslam-demo-test-XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const fs::path out = pattern;
  std::vector<std::string> command = DemoCommand();
  command.insert(command.end(), {"--out", out.string(), "--max-seconds", "60", "--domain", std::to_string(domain.id())});
  testing::ChildProcess::Options options;
  options.log_file = (out / "demo-output.txt").string();
  options.own_process_group = true;  // a demo that outlives the test takes its services with it
  testing::ChildProcess demo(command[0], {command.begin() + 1, command.end()}, options);
  ASSERT_EQ(demo.WaitExit(240s), std::optional<int>(0)) << demo.Tail();
  const std::string output = demo.Output();

  for (const char* file : {"summary.json", "report.txt", "experience_map.png", "occupancy.png", "grid_errors.png", "grid.pgm",
                           "grid.yaml", "experiences.csv"})
    EXPECT_TRUE(fs::exists(out / file) && fs::file_size(out / file) > 0) << file << "\n" << output;
  std::ifstream in(out / "summary.json");
  ASSERT_TRUE(in.good());
  const nlohmann::json summary = nlohmann::json::parse(in);
  for (const char* key : {"complete", "coverage", "map_precision", "frames", "templates", "experiences", "links",
                          "loop_closures", "loop_closure_precision", "ate_m", "ate_odometry_m", "wall_s", "dds"})
    EXPECT_TRUE(summary.contains(key)) << key;
  EXPECT_TRUE(summary["missing"].empty()) << summary.dump(2);
  EXPECT_TRUE(summary["complete"].is_boolean());
  EXPECT_GT(summary["frames"].get<int64_t>(), 0);
  EXPECT_GT(summary["templates"].get<int64_t>(), 0);
  EXPECT_GT(summary["experiences"].get<int64_t>(), 0);
  EXPECT_LE(summary["loop_closures"].get<int64_t>(), summary["links"].get<int64_t>());
  ASSERT_TRUE(summary["coverage"].is_number()) << summary.dump(2);
  EXPECT_GT(summary["coverage"].get<double>(), 0.0);
  EXPECT_LE(summary["coverage"].get<double>(), 1.0);
  ASSERT_TRUE(summary["map_precision"].is_number());
  // Sanity, not the target: 60 s demos on this machine gave 0.43 to 0.93 (heading drift of the
  // visual odometry over hundreds of pirouette turns decides it); a grid in the wrong frame or
  // built from garbage poses lands far lower.
  EXPECT_GT(summary["map_precision"].get<double>(), 0.3);
  EXPECT_LE(summary["map_precision"].get<double>(), 1.0);
  // The grid placed by the start pose alone, beside the fitted placement.
  ASSERT_TRUE(summary["grid"]["at_start_pose"]["coverage"].is_number()) << summary.dump(2);
  EXPECT_LE(summary["grid"]["at_start_pose"]["coverage"].get<double>(), 1.0);
  EXPECT_LE(summary["grid"]["at_start_pose"]["map_precision"].get<double>(), 1.0);
  EXPECT_TRUE(summary["grid_placement"]["theta_rad"].is_number());
  // Where coverage and precision are lost: every reachable cell is covered or missed one way, every
  // marked cell agrees or is wrong one way.
  const nlohmann::json& grid = summary["grid"];
  EXPECT_EQ(grid["covered_cells"].get<int64_t>() + grid["missed_cells"]["unknown"].get<int64_t>() +
                grid["missed_cells"]["uncertain"].get<int64_t>() + grid["missed_cells"]["occupied"].get<int64_t>(),
            grid["reachable_cells"].get<int64_t>())
      << summary.dump(2);
  EXPECT_EQ(grid["agreeing_cells"].get<int64_t>() + grid["wrong_cells"]["free"].get<int64_t>() +
                grid["wrong_cells"]["occupied"].get<int64_t>(),
            grid["marked_cells"].get<int64_t>())
      << summary.dump(2);
  // The start pose places the map frame turned by the experience map's initial facing (the demo
  // keeps OpenRatSLAM's 90 degrees; until session 16 it was left out, a quarter turn off) ...
  const std::vector<double> start = summary["start_pose"].get<std::vector<double>>();
  ASSERT_EQ(start.size(), 3u);
  EXPECT_DOUBLE_EQ(summary["map_origin"]["x_m"].get<double>(), start[0]);
  EXPECT_DOUBLE_EQ(summary["map_origin"]["y_m"].get<double>(), start[1]);
  const double facing = start[2] - summary["map_origin"]["theta_rad"].get<double>();
  EXPECT_NEAR(std::remainder(facing - std::numbers::pi / 2, 2 * std::numbers::pi), 0.0, 1e-9);
  // ... and where the map is better than the odometry, the rigid fit of the map to the truth finds
  // nearly the same turn. (A short run whose map is worse, its heading held to walls' axes fixed
  // 0.28 rad off, was fitted 1.37 rad away: its shape, not its frame, is wrong.)
  if (summary["ate_m"].get<double>() < summary["ate_odometry_m"].get<double>()) {
    const double turn = summary["grid_placement"]["theta_rad"].get<double>() - summary["map_origin"]["theta_rad"].get<double>();
    EXPECT_LT(std::abs(std::remainder(turn, 2 * std::numbers::pi)), 0.6) << summary.dump(2);
  }
  if (summary["loop_closure_precision"].is_number()) {
    EXPECT_GE(summary["loop_closure_precision"].get<double>(), 0.0);
    EXPECT_LE(summary["loop_closure_precision"].get<double>(), 1.0);
    // The farthest loop closure is wrong exactly when some closure is (the mark is 1 m).
    ASSERT_TRUE(summary["loop_closure_farthest_m"].is_number()) << summary.dump(2);
    EXPECT_EQ(summary["loop_closure_farthest_m"].get<double>() > 1.0, !summary["wrong_loop_closures"].empty());
  }
  ASSERT_TRUE(summary["ate_m"].is_number());
  EXPECT_GE(summary["ate_m"].get<double>(), 0.0);
  ASSERT_TRUE(summary["ate_odometry_m"].is_number());
  EXPECT_GE(summary["ate_odometry_m"].get<double>(), 0.0);
  // The final map is judged at its experiences' frames (at most one pair each), the odometry at the
  // same frames (those it has a velocity for), the live path at every frame.
  EXPECT_GE(summary["alignment"]["pairs"].get<int64_t>(), 2);
  EXPECT_LE(summary["alignment"]["pairs"].get<int64_t>(), summary["experiences"].get<int64_t>());
  EXPECT_GE(summary["odometry_alignment"]["pairs"].get<int64_t>(), 2);
  EXPECT_LE(summary["odometry_alignment"]["pairs"].get<int64_t>(), summary["alignment"]["pairs"].get<int64_t>());
  ASSERT_TRUE(summary["live_path"]["ate_m"].is_number()) << summary.dump(2);
  EXPECT_GT(summary["live_path"]["frames"].get<int64_t>(), summary["alignment"]["pairs"].get<int64_t>());
  ASSERT_TRUE(summary["live_path"]["ate_odometry_m"].is_number());
  EXPECT_GT(summary["wall_s"].get<double>(), 0.0);
  if (!summary["recording"].is_null()) {
    const std::string recording = summary["recording"].get<std::string>();
    ASSERT_TRUE(fs::exists(recording));
    // The recording builds the run's map again through the services' libraries (`rslam eval map`):
    // the pose cells give back the recorded actions, and the map is the one the services built.
    // On a loaded machine a view may reach the pose cells after its frame went on without it (one
    // action of 12,140 in a CI run): the replay, which pairs every view with its frame, makes that
    // action with it; the later actions are the same again.
    testing::ChildProcess::Options replay_options;
    replay_options.log_file = (out / "replay-output.txt").string();
    testing::ChildProcess replay(RSLAM_BINARY_DIR "/bin/rslam",
                                 {"eval", "map", recording, "--json", "--out", (out / "replay").string()}, replay_options);
    ASSERT_EQ(replay.WaitExit(120s), std::optional<int>(0)) << replay.Tail();
    const nlohmann::json replayed = nlohmann::json::parse(std::ifstream(out / "replay" / "summary.json"));
    EXPECT_GT(replayed["actions_compared"].get<int64_t>(), summary["frames"].get<int64_t>() - 10) << replayed.dump(2);
    EXPECT_LE(replayed["actions_differing"].get<int64_t>(), replayed["actions_compared"].get<int64_t>() / 1000)
        << replayed.dump(2);
    // The live figure is the experience map's last published map (every map_publish_period_frames,
    // 10, actions), and the services stop together while actions are still in flight: the replay,
    // which applies every recorded action, may have a few experiences more (6 in a loaded run).
    EXPECT_GE(replayed["experiences"].get<int64_t>(), summary["experiences"].get<int64_t>() - 2) << replayed.dump(2);
    EXPECT_LE(replayed["experiences"].get<int64_t>(), summary["experiences"].get<int64_t>() + 10) << replayed.dump(2);
    EXPECT_NEAR(replayed["ate_m"].get<double>(), summary["ate_m"].get<double>(), 0.01);
    EXPECT_NEAR(replayed["coverage"].get<double>(), summary["coverage"].get<double>(), 0.02);
  }
  for (const auto& [name, process] : summary["processes"].items())
    EXPECT_FALSE(process["gave_up"].get<bool>()) << name << " gave up";
  std::error_code ignored;
  if (!HasFailure()) fs::remove_all(out, ignored);  // kept for a look when the test fails
}

}  // namespace
}  // namespace rslam
