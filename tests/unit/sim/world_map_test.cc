#include "tools/sim/world_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <unistd.h>

#include "tests/unit/sim/test_worlds.h"
#include "tools/sim/deterministic_random.h"

namespace rslam::sim {
namespace {

using testing::BoxRoom;
using testing::UwbRoom;
using testing::UwbRoomYamlPath;

TEST(WorldMapTest, LoadsUwbRoomWithItsSizeResolutionAndOrigin) {
  const WorldMap& world = UwbRoom();
  EXPECT_EQ(world.width(), 700);
  EXPECT_EQ(world.height(), 650);
  EXPECT_DOUBLE_EQ(world.resolution(), 0.04);
  EXPECT_DOUBLE_EQ(world.origin().x(), -10.0);
  EXPECT_DOUBLE_EQ(world.origin().y(), -10.0);
}

// Reads the PGM independently and checks every cell's class, which pins the vertical flip (image
// row 0 is the top of the map, cell row 0 the bottom).
TEST(WorldMapTest, ClassifiesEveryPixelWithImageRowZeroAtTheTop) {
  const WorldMap& world = UwbRoom();
  std::ifstream in(std::string(RSLAM_SOURCE_DIR) + "/deploy/worlds/uwb-room.pgm", std::ios::binary);
  ASSERT_TRUE(in);
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t pixels = 700u * 650u;
  ASSERT_GT(data.size(), pixels);
  const char* raster = data.data() + data.size() - pixels;  // the header has no trailing data
  int counts[3] = {0, 0, 0};
  for (int row = 0; row < 650; ++row) {
    for (int col = 0; col < 700; ++col) {
      const int v = static_cast<unsigned char>(raster[row * 700 + col]);
      const CellClass expected = v == 254 ? CellClass::kFree : v == 0 ? CellClass::kOccupied : CellClass::kUnknown;
      ASSERT_EQ(world.Classify(Eigen::Vector2i(col, 649 - row)), expected) << "pixel row " << row << " col " << col;
      ++counts[static_cast<int>(expected)];
    }
  }
  EXPECT_GT(counts[0], 10000);
  EXPECT_GT(counts[1], 1000);
  EXPECT_GT(counts[2], 10000);
  EXPECT_EQ(world.Classify(Eigen::Vector2i(-1, 0)), CellClass::kUnknown);
  EXPECT_TRUE(world.IsWall(Eigen::Vector2i(700, 10)));
}

TEST(WorldMapTest, WorldAndCellConversionsRoundTrip) {
  const WorldMap& world = UwbRoom();
  for (int iy = 0; iy < world.height(); iy += 13) {
    for (int ix = 0; ix < world.width(); ix += 17) {
      const Eigen::Vector2i cell(ix, iy);
      EXPECT_EQ(world.WorldToCell(world.CellCenter(cell)), cell);
    }
  }
  // The origin is the lower-left corner of cell (0, 0).
  EXPECT_EQ(world.WorldToCell(Eigen::Vector2d(-10.0 + 1e-9, -10.0 + 1e-9)), Eigen::Vector2i(0, 0));
  EXPECT_EQ(world.WorldToCell(Eigen::Vector2d(-10.0 - 1e-9, -10.0 + 1e-9)), Eigen::Vector2i(-1, 0));
  EXPECT_EQ(world.WorldToCell(Eigen::Vector2d(-10.0 + 0.041, -10.0 + 0.079)), Eigen::Vector2i(1, 1));
  const Eigen::Vector2d centre = world.CellCenter(Eigen::Vector2i(0, 649));
  EXPECT_NEAR(centre.x(), -9.98, 1e-12);
  EXPECT_NEAR(centre.y(), -10.0 + 649.5 * 0.04, 1e-9);
}

class BrokenWorldFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rslam_sim_world_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Write(const std::string& name, const std::string& content) {
    const auto path = dir_ / name;
    std::ofstream(path, std::ios::binary) << content;
    return path.string();
  }
  std::string GoodPgm() { return std::string("P5\n# c\n3 2\n255\n") + std::string("\xfe\x00\xcd\xfe\xfe\xfe", 6); }
  std::string Yaml(const std::string& image_line, const std::string& extra = "") {
    return image_line + "resolution: 0.05\norigin: [1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
           "free_thresh: 0.196\n" + extra;
  }
  // Loading must fail with a WorldFileError naming the file and containing `problem`.
  void ExpectRefused(const std::string& yaml_path, const std::string& named_file, const std::string& problem) {
    try {
      WorldMap::LoadFromYaml(yaml_path);
      FAIL() << "loaded a broken world, expected: " << problem;
    } catch (const WorldFileError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(named_file), std::string::npos) << what;
      EXPECT_NE(what.find(problem), std::string::npos) << what;
    }
  }

  std::filesystem::path dir_;
};

TEST_F(BrokenWorldFileTest, LoadsAWellFormedSmallWorld) {
  Write("w.pgm", GoodPgm());
  const WorldMap world = WorldMap::LoadFromYaml(Write("w.yaml", Yaml("image: w.pgm\n")));
  EXPECT_EQ(world.width(), 3);
  EXPECT_EQ(world.height(), 2);
  EXPECT_EQ(world.Classify(Eigen::Vector2i(0, 1)), CellClass::kFree);      // top-left pixel 254
  EXPECT_EQ(world.Classify(Eigen::Vector2i(1, 1)), CellClass::kOccupied);  // 0
  EXPECT_EQ(world.Classify(Eigen::Vector2i(2, 1)), CellClass::kUnknown);   // 205
  EXPECT_EQ(world.Classify(Eigen::Vector2i(1, 0)), CellClass::kFree);
  EXPECT_DOUBLE_EQ(world.origin().y(), 2.0);
}

TEST_F(BrokenWorldFileTest, RefusesMissingYaml) {
  ExpectRefused((dir_ / "absent.yaml").string(), "absent.yaml", "does not exist");
}

TEST_F(BrokenWorldFileTest, RefusesMissingImage) {
  ExpectRefused(Write("w.yaml", Yaml("image: nothere.pgm\n")), "nothere.pgm", "does not exist");
}

TEST_F(BrokenWorldFileTest, RefusesMissingOrBadKeys) {
  Write("w.pgm", GoodPgm());
  ExpectRefused(Write("a.yaml", "image: w.pgm\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\n"),
                "a.yaml", "missing key 'resolution'");
  ExpectRefused(Write("b.yaml", Yaml("image: w.pgm\n", "colour: red\n")), "b.yaml", "unknown key 'colour'");
  ExpectRefused(Write("c.yaml", "image: w.pgm\nresolution: fine\norigin: [0, 0, 0]\nnegate: 0\n"
                                "occupied_thresh: 0.65\nfree_thresh: 0.2\n"),
                "c.yaml", "'resolution' must be a number");
  ExpectRefused(Write("d.yaml", "image: w.pgm\nresolution: 0.05\norigin: [0, 0]\nnegate: 0\n"
                                "occupied_thresh: 0.65\nfree_thresh: 0.2\n"),
                "d.yaml", "'origin' must be a list");
  ExpectRefused(Write("e.yaml", "resolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n"
                                "free_thresh: 0.2\n"),
                "e.yaml", "missing key 'image'");
  ExpectRefused(Write("f.yaml", "[1, 2, 3]\n"), "f.yaml", "expected a YAML map");
  ExpectRefused(Write("g.yaml", "image: w.pgm\nresolution: [0.05\n"), "g.yaml", "not valid YAML");
}

TEST_F(BrokenWorldFileTest, RefusesWrongPgm) {
  Write("ascii.pgm", "P2\n3 2\n255\n254 0 205 254 254 254\n");
  ExpectRefused(Write("a.yaml", Yaml("image: ascii.pgm\n")), "ascii.pgm", "expected magic 'P5'");
  Write("short.pgm", "P5\n3 2\n255\n\xfe\x00");
  ExpectRefused(Write("b.yaml", Yaml("image: short.pgm\n")), "short.pgm", "truncated PGM");
  Write("deep.pgm", "P5\n3 2\n65535\n" + std::string(12, '\0'));
  ExpectRefused(Write("c.yaml", Yaml("image: deep.pgm\n")), "deep.pgm", "maxval");
  Write("nosize.pgm", "P5\nthree two\n255\n");
  ExpectRefused(Write("d.yaml", Yaml("image: nosize.pgm\n")), "nosize.pgm", "bad PGM header");
}

// Brute force: march along the ray in 1 mm steps until the point is in a wall cell.
double MarchToWall(const WorldMap& world, const Eigen::Vector2d& from, double angle) {
  const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
  for (double d = 0.0;; d += 0.001) {
    if (world.IsWall(world.WorldToCell(from + d * dir))) return d;
  }
}

TEST(WorldMapTest, RayCastDistanceEqualsBruteForceMarch) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  const std::vector<Eigen::Vector2i> free_cells =
      world.ReachableFreeCells(Eigen::Vector2d(start.x, start.y));
  ASSERT_FALSE(free_cells.empty());
  DeterministicRandom random(42);
  int agree = 0;
  const int rays = 300;
  for (int i = 0; i < rays; ++i) {
    const Eigen::Vector2i cell = free_cells[random.Next() % free_cells.size()];
    const Eigen::Vector2d from =
        world.origin() + world.resolution() * (cell.cast<double>() + Eigen::Vector2d(random.Uniform(), random.Uniform()));
    const double angle = (random.Uniform() * 2.0 - 1.0) * M_PI;
    const RayHit hit = world.CastRay(from, angle);
    const double marched = MarchToWall(world, from, angle);
    // The march can step over the corner of a wall cell the exact ray clips; it is never early.
    EXPECT_LE(hit.distance, marched + 1e-9);
    if (std::abs(hit.distance - marched) <= 0.0011) ++agree;
    EXPECT_TRUE(world.IsWall(hit.cell));
    EXPECT_NEAR((hit.point - from).norm(), hit.distance, 1e-9);
  }
  EXPECT_GE(agree, rays * 97 / 100);
}

TEST(WorldMapTest, RayCastHitsTheNamedFaceOfABoxRoom) {
  const WorldMap world = BoxRoom(50, 30);  // free x in [0.04, 1.96], y in [0.04, 1.16]
  const Eigen::Vector2d from(1.0, 0.6);
  EXPECT_NEAR(world.CastRay(from, 0.0).distance, 0.96, 1e-12);
  EXPECT_EQ(world.CastRay(from, 0.0).face, 0);
  EXPECT_NEAR(world.CastRay(from, M_PI).distance, 0.96, 1e-12);
  EXPECT_EQ(world.CastRay(from, M_PI).face, 1);
  EXPECT_NEAR(world.CastRay(from, M_PI / 2).distance, 0.56, 1e-12);
  EXPECT_EQ(world.CastRay(from, M_PI / 2).face, 2);
  EXPECT_NEAR(world.CastRay(from, -M_PI / 2).distance, 0.56, 1e-12);
  EXPECT_EQ(world.CastRay(from, -M_PI / 2).face, 3);
  EXPECT_DOUBLE_EQ(world.CastRay(Eigen::Vector2d(0.01, 0.6), 0.0).distance, 0.0);  // inside a wall
  EXPECT_DOUBLE_EQ(world.CastRay(Eigen::Vector2d(-50, 0.6), 0.0).distance, 0.0);   // outside the map
  EXPECT_THROW(world.CastRay(from, std::nan("")), std::invalid_argument);
}

TEST(WorldMapTest, ReachableFreeCellsOfAHandmadeMap) {
  // 7 x 5 cells, '#' wall, '.' free, '?' unknown; row 0 of the picture is the top (iy = 4).
  const char* picture[5] = {
      "#######",
      "#..#..#",
      "#..#.?#",
      "#..#..#",
      "#######",
  };
  std::vector<CellClass> cells(35);
  for (int row = 0; row < 5; ++row) {
    for (int ix = 0; ix < 7; ++ix) {
      const char c = picture[row][ix];
      cells[(4 - row) * 7 + ix] = c == '.' ? CellClass::kFree : c == '#' ? CellClass::kOccupied : CellClass::kUnknown;
    }
  }
  const WorldMap world(7, 5, 1.0, Eigen::Vector2d(0, 0), cells);
  const auto left = world.ReachableFreeCells(Eigen::Vector2d(1.5, 1.5));
  ASSERT_EQ(left.size(), 6u);
  EXPECT_EQ(left.front(), Eigen::Vector2i(1, 1));
  EXPECT_EQ(left.back(), Eigen::Vector2i(2, 3));
  for (const auto& c : left) EXPECT_LT(c.x(), 3);
  const auto right = world.ReachableFreeCells(Eigen::Vector2d(4.5, 3.5));
  EXPECT_EQ(right.size(), 5u);  // the unknown cell is not reachable free space
  EXPECT_TRUE(world.ReachableFreeCells(Eigen::Vector2d(3.5, 2.5)).empty());  // start on a wall
  // The default start is in the larger region.
  const Pose2D start = world.DefaultStartPose();
  EXPECT_LT(start.x, 3.0);
}

TEST(WorldMapTest, ReachableCellsForARobotDoNotSqueezeThroughNarrowGaps) {
  // Two 1 m rooms joined by a 2-cell (8 cm) gap in the wall between them.
  const int w = 52, h = 27;
  std::vector<CellClass> cells(w * h, CellClass::kFree);
  for (int iy = 0; iy < h; ++iy) {
    for (int ix = 0; ix < w; ++ix) {
      const bool border = ix == 0 || iy == 0 || ix == w - 1 || iy == h - 1;
      const bool divider = ix == 26 && !(iy == 13 || iy == 14);
      if (border || divider) cells[iy * w + ix] = CellClass::kOccupied;
    }
  }
  const WorldMap world(w, h, 0.04, Eigen::Vector2d(0, 0), cells);
  const Eigen::Vector2d start(0.5, 0.5);
  const auto all = world.ReachableFreeCells(start);
  const auto robot = world.ReachableFreeCells(start, 0.1);
  EXPECT_EQ(all.size(), static_cast<size_t>(50 * 25 - 23));  // both rooms and the gap
  ASSERT_FALSE(robot.empty());
  for (const auto& c : robot) {
    EXPECT_LT(c.x(), 26);
    EXPECT_TRUE(world.IsDiscFree(world.CellCenter(c), 0.1));
  }
  EXPECT_THROW(world.ReachableFreeCells(start, -1.0), std::invalid_argument);
}

TEST(WorldMapTest, DefaultStartIsDeterministicAndFarFromWalls) {
  const WorldMap world = BoxRoom(41, 21);
  const Pose2D start = world.DefaultStartPose();
  EXPECT_EQ(world.WorldToCell(Eigen::Vector2d(start.x, start.y)), Eigen::Vector2i(20, 10));
  const WorldMap& room = UwbRoom();
  const Pose2D a = room.DefaultStartPose();
  const Pose2D b = room.DefaultStartPose();
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(room.Classify(room.WorldToCell(Eigen::Vector2d(a.x, a.y))), CellClass::kFree);
  EXPECT_TRUE(room.IsDiscFree(Eigen::Vector2d(a.x, a.y), 1.0));
  // The building's main free region is large (tens of square metres).
  EXPECT_GT(room.ReachableFreeCells(Eigen::Vector2d(a.x, a.y)).size() * 0.04 * 0.04, 50.0);
}

TEST(WorldMapTest, RefusesInconsistentCells) {
  EXPECT_THROW(WorldMap(3, 3, 0.04, Eigen::Vector2d(0, 0), std::vector<CellClass>(8)), std::invalid_argument);
  EXPECT_THROW(WorldMap(3, 3, 0.0, Eigen::Vector2d(0, 0), std::vector<CellClass>(9)), std::invalid_argument);
  EXPECT_THROW(WorldMap(0, 3, 0.04, Eigen::Vector2d(0, 0), std::vector<CellClass>()), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::sim
