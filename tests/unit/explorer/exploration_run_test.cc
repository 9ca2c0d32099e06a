// Closed-loop exploration: the planner drives a point robot through its own commands, a range
// sensor simulated here (ray casting on the true map, 360 degrees after each pirouette) fills the
// known map, and the run must end by itself with every free cell the robot could reach known.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "services/explorer/exploration_planner.h"

namespace rslam::explorer {
namespace {

struct World {
  int width = 0, height = 0;
  double resolution = 0.04, origin_x = 0.0, origin_y = 0.0;
  std::vector<int8_t> truth;  // ROS convention, row 0 = bottom
  bool IsFree(int x, int y) const {
    return x >= 0 && y >= 0 && x < width && y < height && truth[y * width + x] == 0;
  }
  GridView View(const std::vector<int8_t>& cells) const {
    return GridView{width, height, resolution, origin_x, origin_y, cells};
  }
};

// map_server PGM: 254 free, 0 occupied, 205 unknown; the first image row is the top of the map.
World LoadMapServerWorld(const std::filesystem::path& pgm, double resolution, double ox, double oy) {
  const cv::Mat image = cv::imread(pgm.string(), cv::IMREAD_UNCHANGED);
  World world;
  if (image.empty()) return world;
  world.width = image.cols;
  world.height = image.rows;
  world.resolution = resolution;
  world.origin_x = ox;
  world.origin_y = oy;
  world.truth.resize(image.total());
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c) {
      const uchar v = image.at<uchar>(r, c);
      world.truth[(image.rows - 1 - r) * image.cols + c] = v >= 250 ? 0 : (v <= 50 ? 100 : -1);
    }
  return world;
}

// 360-degree range sensor: marks cells along each ray free until the first non-free true cell,
// which is marked occupied.
void Sense(const World& world, std::vector<int8_t>& known, const Pose2D& p, double range_m, int rays) {
  const double step = world.resolution * 0.5;
  for (int i = 0; i < rays; ++i) {
    const double a = 2.0 * M_PI * i / rays, c = std::cos(a), s = std::sin(a);
    for (double r = 0.0; r <= range_m; r += step) {
      const int x = static_cast<int>(std::floor((p.x + r * c - world.origin_x) / world.resolution));
      const int y = static_cast<int>(std::floor((p.y + r * s - world.origin_y) / world.resolution));
      if (x < 0 || y < 0 || x >= world.width || y >= world.height) break;
      if (!world.IsFree(x, y)) {
        known[y * world.width + x] = 100;
        break;
      }
      known[y * world.width + x] = 0;
    }
  }
}

bool SegmentIsFree(const World& world, const Pose2D& from, double distance) {
  for (double r = 0.0; r <= distance; r += world.resolution * 0.25) {
    const int x = static_cast<int>(std::floor((from.x + r * std::cos(from.theta) - world.origin_x) / world.resolution));
    const int y = static_cast<int>(std::floor((from.y + r * std::sin(from.theta) - world.origin_y) / world.resolution));
    if (!world.IsFree(x, y)) return false;
  }
  return true;
}

struct RunResult {
  bool complete = false;
  int plans = 0, pirouettes = 0, moves = 0, blocked = 0;
  double turned_rad = 0.0, driven_m = 0.0;  // turns of the plans (pirouettes not counted)
  std::vector<int8_t> known;
};

RunResult Explore(const World& world, const ExplorerConfig& config, Pose2D robot, double sensor_range, int rays,
                  int max_plans) {
  ExplorationPlanner planner(config);
  RunResult run;
  run.known.assign(world.truth.size(), -1);
  for (; run.plans < max_plans; ++run.plans) {
    const Plan plan = planner.PlanFrom(world.View(run.known), robot);
    if (plan.complete) {
      run.complete = true;
      break;
    }
    for (const MotionCommand& cmd : plan.commands) {
      if (cmd.kind == MotionCommand::Kind::kRotate) {
        robot.theta = std::remainder(robot.theta + cmd.angle_rad, 2 * M_PI);
        run.turned_rad += std::abs(cmd.angle_rad);
      } else if (cmd.kind == MotionCommand::Kind::kMove) {
        if (!planner.IsPathClear(world.View(run.known), robot, cmd.distance_m)) {
          planner.ReportBlocked(plan);
          ++run.blocked;
          break;  // replan from here
        }
        EXPECT_TRUE(SegmentIsFree(world, robot, cmd.distance_m)) << "drove through an obstacle";
        robot.x += cmd.distance_m * std::cos(robot.theta);
        robot.y += cmd.distance_m * std::sin(robot.theta);
        run.driven_m += std::abs(cmd.distance_m);
        ++run.moves;
      } else if (cmd.kind == MotionCommand::Kind::kPirouette) {
        Sense(world, run.known, robot, sensor_range, rays);
        planner.RecordPirouette(robot);
        ++run.pirouettes;
      }
    }
  }
  return run;
}

// The oracle: exploration cells free in the TRUE configuration space and connected to the start;
// every free cell inside them must end up known.
int CountUnknownReachableFreeCells(const World& world, const ExplorerConfig& config, const Pose2D& start,
                                   const std::vector<int8_t>& known, int* reachable_free_cells) {
  const CoarseGrid truth = BuildConfigurationSpace(world.View(world.truth), config);
  std::vector<uint8_t> seen(truth.cells.size(), 0);
  std::deque<std::pair<int, int>> queue{{truth.CellX(start.x), truth.CellY(start.y)}};
  seen[queue.front().second * truth.width + queue.front().first] = 1;
  auto free = [&](int x, int y) { return truth.Contains(x, y) && truth.At(x, y) == CellClass::kFree; };
  while (!queue.empty()) {
    auto [x, y] = queue.front();
    queue.pop_front();
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (!free(nx, ny) || seen[ny * truth.width + nx]) continue;
        if (dx && dy && !(free(nx, y) && free(x, ny))) continue;
        seen[ny * truth.width + nx] = 1;
        queue.emplace_back(nx, ny);
      }
  }
  int unknown = 0;
  *reachable_free_cells = 0;
  const int f = config.coarse_cell_factor;
  for (int y = 0; y < world.height; ++y)
    for (int x = 0; x < world.width; ++x) {
      if (!seen[(y / f) * truth.width + x / f] || !world.IsFree(x, y)) continue;
      ++*reachable_free_cells;
      if (known[y * world.width + x] < 0) ++unknown;
    }
  return unknown;
}

TEST(ExplorationRunTest, ExploresASmallTwoRoomWorldCompletely) {
  // 4 m x 2.4 m, 4 cm cells, two rooms joined by an 80 cm door, a pillar in the left room.
  World world;
  world.width = 100;
  world.height = 60;
  world.truth.assign(world.width * world.height, 0);
  auto wall = [&](int x0, int y0, int x1, int y1) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) world.truth[y * world.width + x] = 100;
  };
  wall(0, 0, 99, 0); wall(0, 59, 99, 59); wall(0, 0, 0, 59); wall(99, 0, 99, 59);
  wall(55, 0, 56, 19); wall(55, 40, 56, 59);  // door at y = 20..39
  wall(20, 20, 25, 30);                        // pillar
  ExplorerConfig config;
  config.robot_radius_m = 0.08;
  config.coarse_cell_factor = 3;
  const Pose2D start{0.3, 0.3, 0.0};
  const RunResult run = Explore(world, config, start, 1.5, 720, 500);
  EXPECT_TRUE(run.complete);
  int reachable = 0;
  EXPECT_EQ(CountUnknownReachableFreeCells(world, config, start, run.known, &reachable), 0);
  EXPECT_GT(reachable, 2500);  // both rooms
  int right_room_known = 0;
  for (int y = 1; y < 59; ++y)
    for (int x = 57; x < 99; ++x) right_room_known += run.known[y * world.width + x] == 0;
  EXPECT_GT(right_room_known, 1500);
  EXPECT_GT(run.moves, 1);
}

TEST(ExplorationRunTest, ExploresTheUwbRoomMapUntilNoReachableUnknownRemains) {
  const char* data = std::getenv("RSLAM_SHARED_DATA");
  if (data == nullptr || !std::filesystem::exists(std::filesystem::path(data) / "worlds/uwb-room.pgm"))
    GTEST_SKIP() << "RSLAM_SHARED_DATA/worlds/uwb-room.pgm not available";
  // worlds/uwb-room.yaml: resolution 0.04, origin [-10, -10, 0].
  const World world = LoadMapServerWorld(std::filesystem::path(data) / "worlds/uwb-room.pgm", 0.04, -10.0, -10.0);
  ASSERT_EQ(world.width, 700);
  ASSERT_EQ(world.height, 650);
  ExplorerConfig config;
  config.robot_radius_m = 0.12;
  config.coarse_cell_factor = 4;  // 16 cm exploration cells
  // Start at the free exploration cell nearest the map centre, in the true configuration space.
  const CoarseGrid truth = BuildConfigurationSpace(world.View(world.truth), config);
  Pose2D start;
  double best = 1e9;
  for (int y = 0; y < truth.height; ++y)
    for (int x = 0; x < truth.width; ++x) {
      if (truth.At(x, y) != CellClass::kFree) continue;
      const double d = std::hypot(x - truth.width / 2.0, y - truth.height / 2.0);
      if (d < best) { best = d; start = {truth.CentreX(x), truth.CentreY(y), 0.0}; }
    }
  ASSERT_LT(best, 1e9);
  // Along the grid path and straightened: both explore the whole room; straightened, the robot
  // turns on the spot less.
  double turned_along_the_grid = 0.0;
  for (bool straighten : {false, true}) {
    config.straighten_paths = straighten;
    const RunResult run = Explore(world, config, start, 2.5, 1080, 3000);
    EXPECT_TRUE(run.complete) << "after " << run.plans << " plans";
    int reachable = 0;
    const int unknown = CountUnknownReachableFreeCells(world, config, start, run.known, &reachable);
    EXPECT_EQ(unknown, 0) << "of " << reachable << " reachable free cells";
    EXPECT_GT(reachable, 10000);
    if (straighten) {
      EXPECT_LT(run.turned_rad, turned_along_the_grid);
      RecordProperty("plans", run.plans);
      RecordProperty("pirouettes", run.pirouettes);
      RecordProperty("moves", run.moves);
    } else {
      turned_along_the_grid = run.turned_rad;
    }
    std::printf("uwb-room, straighten_paths %d: %d plans, %d pirouettes, %d moves (%.1f m), turned %.1f rad, %d blocked, "
                "%d reachable free cells\n",
                straighten, run.plans, run.pirouettes, run.moves, run.driven_m, run.turned_rad, run.blocked, reachable);
  }
}

}  // namespace
}  // namespace rslam::explorer
