#include "services/occupancy/anchored_profile_map.h"

#include <gtest/gtest.h>

#include <map>
#include <stop_token>
#include <thread>

namespace rslam::occupancy {
namespace {

GridConfig Grid() { return GridConfig{0.02, 200, 200, -2.0, -2.0}; }
SensorModelConfig Model() {
  SensorModelConfig m;
  m.reliable_range_m = 0.5;
  m.footprint_radius_m = 0.05;
  return m;
}
// An obstacle 0.315 m straight ahead of the robot, nothing else.
RadialObstacleProfile ObstacleAhead() {
  RadialObstacleProfile p;
  p.first_bearing_rad = -0.005;
  p.bin_width_rad = 0.01;
  p.bins.push_back(RopBin{0.315f, 0.07f, BinStatus::kObstacle});
  return p;
}

TEST(AnchoredProfileMapTest, MovingAnExperienceMovesItsProfilesCells) {
  AnchoredProfileMap map(Grid(), Model());
  const Pose2D experience{0.5, 0.0, 0.0};
  const Pose2D robot{0.61, 0.11, M_PI / 2};  // 11 cm ahead and left of the experience, facing +y
  map.AddProfile(7, experience, robot, ObstacleAhead());
  const CellIndex before = map.grid().CellOf(0.61, 0.425);
  EXPECT_GT(map.grid().Probability(before), 0.6);
  EXPECT_TRUE(map.grid().UnderFootprint(map.grid().CellOf(0.61, 0.11)));

  // Loop closure moves experience 7 by (-1, +0.2) and turns it by +90 degrees.
  const std::map<uint64_t, Pose2D> corrected{{7, {-0.5, 0.2, M_PI / 2}}};
  const size_t moved = map.Rebuild([&](uint64_t id) -> std::optional<Pose2D> {
    auto it = corrected.find(id);
    return it == corrected.end() ? std::nullopt : std::optional<Pose2D>(it->second);
  });
  EXPECT_EQ(moved, 1u);
  // Robot offset (0.11, 0.11, +90 deg) from the corrected experience: robot at (-0.61, 0.31)
  // facing -x, so the obstacle is now at (-0.925, 0.31) and the old cell is unknown again.
  EXPECT_FALSE(map.grid().IsKnown(before));
  EXPECT_GT(map.grid().Probability(map.grid().CellOf(-0.925, 0.31)), 0.6);
  // The floor under the robot moves with it.
  EXPECT_FALSE(map.grid().UnderFootprint(map.grid().CellOf(0.61, 0.11)));
  EXPECT_TRUE(map.grid().UnderFootprint(map.grid().CellOf(-0.61, 0.31)));
}

TEST(AnchoredProfileMapTest, AFrameAddsAViewOnlyAfterTheRobotMovedOrTurnedOrTheExperienceChanged) {
  AnchoredProfileMap map(Grid(), Model());
  const Pose2D experience{0.5, 0.0, M_PI / 2};
  EXPECT_TRUE(map.IsNewView(7, Between(experience, {0.5, 0.1, M_PI / 2}), 0.08, 0.25));  // the first
  map.AddProfile(7, experience, {0.5, 0.1, M_PI / 2}, ObstacleAhead());
  EXPECT_FALSE(map.IsNewView(7, Between(experience, {0.5, 0.1, M_PI / 2}), 0.08, 0.25));        // standing
  EXPECT_FALSE(map.IsNewView(7, Between(experience, {0.5, 0.17, M_PI / 2 + 0.2}), 0.08, 0.25));  // 7 cm, 0.2 rad
  EXPECT_TRUE(map.IsNewView(7, Between(experience, {0.5, 0.19, M_PI / 2}), 0.08, 0.25));         // 9 cm
  EXPECT_TRUE(map.IsNewView(7, Between(experience, {0.5, 0.1, M_PI / 2 - 0.3}), 0.08, 0.25));    // 0.3 rad
  EXPECT_TRUE(map.IsNewView(7, Between(experience, {0.5, 0.1, -M_PI / 2}), 0.08, 0.25));         // turned round
  EXPECT_TRUE(map.IsNewView(8, Between({0.5, 0.1, M_PI / 2}, {0.5, 0.1, M_PI / 2}), 0.08, 0.25));  // a new experience
  // Offsets from the experience, not map poses: a corrected experience moves the robot with it.
  EXPECT_FALSE(map.IsNewView(7, Between({1.5, 0.0, M_PI / 2}, {1.5, 0.1, M_PI / 2}), 0.08, 0.25));
  EXPECT_TRUE(map.IsNewView(7, Between(experience, {0.5, 0.1, M_PI / 2}), 0.0, 0.0));  // spacing 0: every frame
}

TEST(AnchoredProfileMapTest, UnknownExperiencesKeepTheirPoseOnRebuild) {
  AnchoredProfileMap map(Grid(), Model());
  map.AddProfile(1, {0, 0, 0}, {0, 0, 0}, ObstacleAhead());
  const std::vector<int8_t> before = map.grid().ToRosCells();
  EXPECT_EQ(map.Rebuild([](uint64_t) { return std::nullopt; }), 0u);
  EXPECT_EQ(map.grid().ToRosCells(), before);
}

TEST(AnchoredProfileMapTest, SavedStateLoadsIntoTheSameGrid) {
  AnchoredProfileMap map(Grid(), Model());
  map.AddProfile(1, {0, 0, 0}, {0.1, 0.0, 0.2}, ObstacleAhead());
  map.AddProfile(2, {0.5, 0.5, 1.0}, {0.4, 0.6, 2.0}, ObstacleAhead());
  map.Rebuild([](uint64_t id) -> std::optional<Pose2D> {
    if (id == 2) return Pose2D{0.45, 0.55, 1.1};
    return std::nullopt;
  });
  const std::string bytes = map.ToProto().SerializeAsString();
  proto::OccupancyState state;
  ASSERT_TRUE(state.ParseFromString(bytes));
  const AnchoredProfileMap loaded = AnchoredProfileMap::FromProto(state);
  ASSERT_EQ(loaded.profiles().size(), 2u);
  EXPECT_EQ(loaded.profiles()[1].experience_id, 2u);
  EXPECT_DOUBLE_EQ(loaded.profiles()[1].experience_pose.theta, 1.1);
  EXPECT_EQ(loaded.grid().ToRosCells(), map.grid().ToRosCells());
  EXPECT_EQ(loaded.grid().grid_config().width, 200);
}

TEST(AnchoredProfileMapTest, AReplayOnAnotherThreadWhileProfilesKeepComingGivesTheRebuiltGrid) {
  // The occupancy node's rebuild: plan, replay on another thread while new profiles are added,
  // adopt. It must give the grid of a rebuild made with every profile at once.
  auto fill = [](AnchoredProfileMap& map, int first, int count) {
    for (int i = first; i < first + count; ++i) {
      const Pose2D experience{0.05 * i, 0.02 * (i % 5), 0.1 * i};
      map.AddProfile(static_cast<uint64_t>(i % 4), experience, Compose(experience, {0.1, 0.0, 0.3}), ObstacleAhead());
    }
  };
  const auto corrected = [](uint64_t id) -> std::optional<Pose2D> {
    if (id == 3) return std::nullopt;  // an experience the correction does not know keeps its pose
    return Pose2D{-0.3 * static_cast<double>(id), 0.2, 0.5 * static_cast<double>(id)};
  };
  AnchoredProfileMap at_once(Grid(), Model()), threaded(Grid(), Model());
  fill(at_once, 0, 40);
  fill(threaded, 0, 40);
  const size_t moved = at_once.Rebuild(corrected);
  fill(at_once, 40, 40);

  AnchoredProfileMap::RebuildPlan plan = threaded.PlanRebuild(corrected);
  EXPECT_EQ(plan.moved, moved);
  EXPECT_EQ(plan.placements.size(), 40u);
  std::optional<OccupancyGrid> replayed;
  std::thread replay([&] { replayed = AnchoredProfileMap::Replay(plan); });
  fill(threaded, 40, 40);  // profiles kept meanwhile go into the live grid, then into the new one
  replay.join();
  const std::vector<int8_t> live = threaded.grid().ToRosCells();
  threaded.Adopt(std::move(*replayed), plan);
  EXPECT_EQ(threaded.grid().ToRosCells(), at_once.grid().ToRosCells());
  EXPECT_NE(live, at_once.grid().ToRosCells()) << "the live grid kept the old anchors until the adopt";
}

TEST(AnchoredProfileMapTest, AStoppedReplayIsDroppedAndTheNextPlanGivesTheNewestMapsGrid) {
  // The occupancy node's stop: the replay of an older correction is stopped for the newer one
  // waiting and never adopted. The next plan starts from the anchors the stopped plan moved and
  // must give the grid of a rebuild on the newer correction alone.
  const auto older = [](uint64_t id) -> std::optional<Pose2D> { return Pose2D{0.3 * static_cast<double>(id), -0.1, 0.2}; };
  const auto newer = [](uint64_t id) -> std::optional<Pose2D> {
    return Pose2D{-0.3 * static_cast<double>(id), 0.2, 0.5 * static_cast<double>(id)};
  };
  AnchoredProfileMap direct(Grid(), Model()), stopped(Grid(), Model());
  for (AnchoredProfileMap* map : {&direct, &stopped})
    for (int i = 0; i < 40; ++i) {
      const Pose2D experience{0.05 * i, 0.02 * (i % 5), 0.1 * i};
      map->AddProfile(static_cast<uint64_t>(i % 4), experience, Compose(experience, {0.1, 0.0, 0.3}), ObstacleAhead());
    }
  direct.Rebuild(newer);

  AnchoredProfileMap::RebuildPlan plan = stopped.PlanRebuild(older);
  std::stop_source stop;
  stop.request_stop();
  EXPECT_FALSE(AnchoredProfileMap::Replay(plan, stop.get_token()));
  const std::vector<int8_t> before = stopped.grid().ToRosCells();
  AnchoredProfileMap::RebuildPlan next = stopped.PlanRebuild(newer);
  std::optional<OccupancyGrid> replayed = AnchoredProfileMap::Replay(next);
  ASSERT_TRUE(replayed);
  stopped.Adopt(std::move(*replayed), next);
  EXPECT_EQ(stopped.grid().ToRosCells(), direct.grid().ToRosCells());
  EXPECT_NE(before, direct.grid().ToRosCells()) << "the correction must change the grid for this to tell";
}

TEST(AnchoredProfileMapTest, RefusesCorruptStateWhole) {
  AnchoredProfileMap map(Grid(), Model());
  map.AddProfile(1, {0, 0, 0}, {0, 0, 0}, ObstacleAhead());
  proto::OccupancyState bad_status = map.ToProto();
  bad_status.mutable_profiles(0)->set_status(std::string(1, '\x09'));
  EXPECT_THROW(AnchoredProfileMap::FromProto(bad_status), std::invalid_argument);
  proto::OccupancyState short_ranges = map.ToProto();
  short_ranges.mutable_profiles(0)->clear_range_m();
  EXPECT_THROW(AnchoredProfileMap::FromProto(short_ranges), std::invalid_argument);
  proto::OccupancyState bad_grid = map.ToProto();
  bad_grid.mutable_grid()->set_resolution_m(-1);
  EXPECT_THROW(AnchoredProfileMap::FromProto(bad_grid), std::invalid_argument);
  EXPECT_THROW(map.AddProfile(1, {NAN, 0, 0}, {0, 0, 0}, ObstacleAhead()), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::occupancy
