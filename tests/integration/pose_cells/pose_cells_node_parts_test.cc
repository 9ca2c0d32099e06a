// The pieces the pose-cell service is built from, without the bus: the frame joiner, the
// resynchronisation API of the network, and the scripted drive the process tests use.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "services/pose_cells/pose_cell_network.h"
#include "services/pose_cells/velocity_view_joiner.h"
#include "tests/integration/pose_cells/scripted_loop.h"

namespace rslam::pose_cells {
namespace {

using Joiner = VelocityViewJoiner<int, std::string>;

std::vector<uint64_t> Seqs(const std::vector<Joiner::Frame>& frames) {
  std::vector<uint64_t> out;
  for (const auto& f : frames) out.push_back(f.frame_seq);
  return out;
}

TEST(VelocityViewJoinerTest, ReleasesFramesInOrderWhenTheTwoStreamsInterleave) {
  Joiner joiner(20, 0);
  joiner.AddView(0, "v0");
  joiner.AddView(1, "v1");
  joiner.AddView(2, "v2");
  EXPECT_TRUE(joiner.TakeReady().empty());  // odometry of frame 0 may still come
  joiner.AddVelocity(0, 10);
  auto ready = joiner.TakeReady();
  ASSERT_EQ(Seqs(ready), (std::vector<uint64_t>{0}));
  EXPECT_EQ(*ready[0].velocity, 10);
  EXPECT_EQ(*ready[0].view, "v0");
  joiner.AddVelocity(1, 11);
  joiner.AddVelocity(2, 12);
  ready = joiner.TakeReady();
  ASSERT_EQ(Seqs(ready), (std::vector<uint64_t>{1, 2}));
  EXPECT_EQ(*ready[1].velocity, 12);
  EXPECT_EQ(joiner.incomplete(), 0u);
  EXPECT_EQ(joiner.waiting(), 0u);
}

TEST(VelocityViewJoinerTest, FrameWhoseOdometryStreamMovedPastItGoesOnWithTheView) {
  Joiner joiner(20, 0);
  joiner.AddView(0, "v0");
  joiner.AddView(1, "v1");
  joiner.AddVelocity(1, 11);  // odometry of frame 0 never came (its stream is in frame order)
  auto ready = joiner.TakeReady();
  ASSERT_EQ(Seqs(ready), (std::vector<uint64_t>{0, 1}));
  EXPECT_FALSE(ready[0].velocity);
  EXPECT_EQ(*ready[0].view, "v0");
  EXPECT_EQ(joiner.incomplete(), 1u);
  EXPECT_FALSE(joiner.AddVelocity(0, 10));  // late: refused
  EXPECT_EQ(joiner.stale(), 1u);
}

TEST(VelocityViewJoinerTest, DeadViewStreamIsWaitedForUntilOdometryIsAWindowAhead) {
  Joiner joiner(5, 0);
  joiner.AddView(0, "v0");
  joiner.AddVelocity(0, 10);
  EXPECT_EQ(Seqs(joiner.TakeReady()), (std::vector<uint64_t>{0}));
  for (int s = 1; s <= 5; ++s) {
    joiner.AddVelocity(s, 10 + s);
    EXPECT_TRUE(joiner.TakeReady().empty()) << s;
  }
  joiner.AddVelocity(6, 16);  // 5 frames ahead of frame 1
  EXPECT_EQ(Seqs(joiner.TakeReady()), (std::vector<uint64_t>{1}));
  EXPECT_EQ(joiner.incomplete(), 1u);
}

TEST(VelocityViewJoinerTest, BurstOfOneStreamWaitsForTheOtherUntilTheFrameIsOldEnough) {
  Joiner joiner(5, 1000);
  for (int s = 0; s <= 10; ++s) joiner.AddVelocity(s, s, /*now_ns=*/s);
  EXPECT_TRUE(joiner.TakeReady(/*now_ns=*/999).empty());  // far ahead, but frame 0 is young
  joiner.AddView(0, "v0", 999);
  EXPECT_EQ(Seqs(joiner.TakeReady(999)), (std::vector<uint64_t>{0}));
  auto ready = joiner.TakeReady(/*now_ns=*/1005);  // 1-5 waited long enough; 6.. are not far behind
  EXPECT_EQ(Seqs(ready), (std::vector<uint64_t>{1, 2, 3, 4, 5}));
  EXPECT_EQ(joiner.incomplete(), 5u);
}

TEST(VelocityViewJoinerTest, RefusedSideLetsTheFrameGoOnAtOnce) {
  Joiner joiner(20, 0);
  joiner.AddVelocity(0, 10);
  joiner.SkipView(0);
  auto ready = joiner.TakeReady();
  ASSERT_EQ(Seqs(ready), (std::vector<uint64_t>{0}));
  EXPECT_FALSE(ready[0].view);
}

TEST(VelocityViewJoinerTest, CameraRestartingItsNumberingStartsOver) {
  Joiner joiner(5, 0);
  for (int s = 0; s < 100; ++s) {
    joiner.AddVelocity(s, s);
    joiner.AddView(s, "v");
  }
  EXPECT_EQ(joiner.TakeReady().size(), 100u);
  EXPECT_TRUE(joiner.AddVelocity(0, 0));
  EXPECT_TRUE(joiner.AddView(0, "v"));
  EXPECT_EQ(Seqs(joiner.TakeReady()), (std::vector<uint64_t>{0}));
}

// The scripted drive of the process tests: experiences along lap 1, then the first view of
// lap 2 closes the loop onto experience 0.
TEST(ScriptedLoopTest, CreatesExperiencesThenLinksBackToTheFirstWhenItsViewReturns) {
  PoseCellNetwork network(PoseCellConfig{});
  std::vector<Action> actions;
  for (const auto& f : testing::ScriptedLoop(2 * testing::kLapFrames)) {
    actions.push_back(network.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s, MatchOf(f)));
  }
  int creates_in_lap_1 = 0;
  for (int i = 0; i < testing::kLapFrames; ++i) {
    ASSERT_NE(actions[i].kind, Action::Kind::kLink) << i;
    creates_in_lap_1 += actions[i].kind == Action::Kind::kCreate;
  }
  EXPECT_GE(creates_in_lap_1, 8);
  int first_link = -1;
  for (int i = testing::kLapFrames; i < 2 * testing::kLapFrames && first_link < 0; ++i) {
    if (actions[i].kind == Action::Kind::kLink) first_link = i;
  }
  ASSERT_GE(first_link, testing::kLapFrames);
  EXPECT_LE(first_link, testing::kLapFrames + 2);
  EXPECT_EQ(actions[first_link].experience_id, 0u);
}

// After a restart from an older state, the network takes the map's experiences: the next id it
// creates is the map's next id, and templates it never saw are placed when they are next seen.
TEST(AdoptExperienceMapTest, NextCreatedIdFollowsTheMapsExperiences) {
  const auto frames = testing::ScriptedLoop(testing::kLapFrames);
  PoseCellNetwork ahead(PoseCellConfig{});
  PoseCellNetwork behind(PoseCellConfig{});
  std::vector<MapExperience> map;
  for (int i = 0; i < testing::kLapFrames; ++i) {
    const auto& f = frames[i];
    const Action a = ahead.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s, MatchOf(f));
    if (a.kind == Action::Kind::kCreate) map.push_back({a.template_id, {a.pc_x, a.pc_y, a.pc_th}});
    if (i < 30) {
      behind.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s, MatchOf(f));
    }
  }
  ASSERT_GT(map.size(), behind.experience_count());
  std::vector<std::pair<uint32_t, uint32_t>> links;
  for (uint32_t i = 1; i < map.size(); ++i) links.emplace_back(i - 1, i);
  const uint32_t current = static_cast<uint32_t>(map.size() - 1);
  behind.AdoptExperienceMap(map, links, current);
  EXPECT_EQ(behind.experience_count(), map.size());
  EXPECT_EQ(behind.template_count(), ahead.template_count());
  EXPECT_NEAR(behind.BestPose().x, map[current].cell.x, 0.5);  // the packet restarts in that cell
  // Drive on past the adopted experiences: the next create carries the map's next id.
  Action next;
  for (uint64_t i = testing::kLapFrames; next.kind != Action::Kind::kCreate && i < 3 * testing::kLapFrames; ++i) {
    auto f = testing::ScriptedLoopFrame(i);
    f.view.template_id = testing::kTemplatesPerLap + static_cast<uint32_t>(i);  // new places
    next = behind.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s,
                               {behind.template_count(), true, 0.0});
  }
  EXPECT_EQ(next.kind, Action::Kind::kCreate);
  EXPECT_EQ(next.experience_id, map.size());
  EXPECT_EQ(next.from_experience_id, current);
}

TEST(AdoptExperienceMapTest, RefusesOutOfRangeCellsAndUnknownIdsUnchanged) {
  PoseCellNetwork network(PoseCellConfig{});
  EXPECT_THROW(network.AdoptExperienceMap({{0, {1e9, 0, 0}}}, {}, 0), std::invalid_argument);
  EXPECT_THROW(network.AdoptExperienceMap({{0, {1, 1, 1}}}, {{0, 5}}, 0), std::invalid_argument);
  EXPECT_THROW(network.AdoptExperienceMap({{0, {1, 1, 1}}}, {}, 3), std::invalid_argument);
  EXPECT_EQ(network.experience_count(), 0u);
  EXPECT_EQ(network.template_count(), 0u);
}

TEST(SkipTemplatesTest, SkippedTemplateIsPlacedAtItsFirstSightingAndInjectsNothingBefore) {
  PoseCellNetwork network(PoseCellConfig{});
  network.ProcessFrame(0, 0, 0.1, {0, true, 0.0});
  network.SkipTemplates(5);
  EXPECT_EQ(network.template_count(), 5u);
  EXPECT_THROW(network.SkipTemplates(2), std::invalid_argument);
  // Template 3 seen for the first time: associated, like a new one; a valid frame.
  EXPECT_NO_THROW(network.ProcessFrame(1.0, 0, 0.1, {3, false, 0.0}));
  const proto::State saved = network.SaveState();
  PoseCellNetwork restored(PoseCellConfig{});
  restored.LoadState(saved);
  EXPECT_EQ(restored.SaveState().SerializeAsString(), saved.SerializeAsString());
}

}  // namespace
}  // namespace rslam::pose_cells
