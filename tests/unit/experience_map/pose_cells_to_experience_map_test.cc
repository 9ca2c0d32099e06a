// The pose cells' explicit-id actions drive the experience map without desynchronising ids,
// through a loop closure and after either side is saved and reloaded mid-run.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "services/experience_map/experience_map.h"
#include "services/pose_cells/pose_cell_network.h"

namespace rslam {
namespace {

experience_map::ExperienceAction ToExperienceAction(const pose_cells::Action& a) {
  experience_map::ExperienceAction e;
  switch (a.kind) {
    case pose_cells::Action::Kind::kNone: e.kind = experience_map::ExperienceAction::Kind::kNone; break;
    case pose_cells::Action::Kind::kCreate: e.kind = experience_map::ExperienceAction::Kind::kCreate; break;
    case pose_cells::Action::Kind::kLink: e.kind = experience_map::ExperienceAction::Kind::kLink; break;
    case pose_cells::Action::Kind::kSet: e.kind = experience_map::ExperienceAction::Kind::kSet; break;
  }
  e.experience_id = a.experience_id;
  e.from_experience_id = a.from_experience_id;
  e.template_id = a.template_id;
  e.relative_angle_rad = a.relative_angle_rad;
  e.offset_x_m = a.offset_x_m;
  e.offset_y_m = a.offset_y_m;
  e.pc_x = a.pc_x;
  e.pc_y = a.pc_y;
  e.pc_th = a.pc_th;
  e.sequence = a.sequence;
  return e;
}

TEST(PoseCellsToExperienceMap, TwoLapsOfASquareKeepIdsInStepAndCloseTheLoop) {
  pose_cells::PoseCellNetwork cells(pose_cells::PoseCellConfig{});
  auto map = std::make_unique<experience_map::ExperienceMap>(experience_map::ExperienceMapConfig{});
  const double quarter = std::numbers::pi / 2;
  constexpr int kFramesPerLap = 16;
  int links = 0;
  uint64_t expected_sequence = 0;
  for (int frame = 0; frame < 3 * kFramesPerLap; ++frame) {
    const int j = frame % kFramesPerLap;
    const bool turn = j % 4 == 3;
    const double v = turn ? 0.0 : 2.0, w = turn ? quarter : 0.0;
    const bool first_lap = frame < kFramesPerLap;
    const pose_cells::Action a =
        cells.ProcessFrame(v, w, 1.0, {static_cast<uint32_t>(j), first_lap, 0.0});
    map->Integrate(v, w, 1.0);
    if (a.kind != pose_cells::Action::Kind::kNone) {
      ASSERT_EQ(a.sequence, expected_sequence++);
      if (a.kind == pose_cells::Action::Kind::kLink) ++links;
    }
    ASSERT_NO_THROW(map->Apply(ToExperienceAction(a))) << "frame " << frame;
    if (frame == kFramesPerLap + 5) {  // restart the experience map from its saved state
      const auto saved = map->Save();
      map = std::make_unique<experience_map::ExperienceMap>(experience_map::ExperienceMapConfig{});
      map->Load(saved);
    }
  }
  EXPECT_EQ(map->experiences().size(), cells.experience_count());
  EXPECT_EQ(cells.experience_count(), static_cast<uint32_t>(kFramesPerLap));  // no new places
  EXPECT_GE(links, 1);
  map->Relax(200);
  EXPECT_LT(map->MaxLinkError(), 0.5);
}

}  // namespace
}  // namespace rslam
