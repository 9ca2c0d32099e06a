#include "services/occupancy/profile_message.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace rslam::occupancy {
namespace {

// One bin of each kind, as the pipeline makes them: an obstacle, floor seen free only as far as
// the image's side (0.93 m, short of the 1.5 m reliable range), floor free to the reliable range,
// an obstacle filling the view, and a bearing no view covered.
AnchoredProfile Profile() {
  AnchoredProfile a;
  a.experience_id = 7;
  a.offset = {0.11, -0.04, 0.2};
  a.profile.first_bearing_rad = -0.5;
  a.profile.bin_width_rad = 0.2;
  a.profile.bins = {RopBin{0.62f, 0.31f, BinStatus::kObstacle}, RopBin{0.93f, 0.31f, BinStatus::kFree},
                    RopBin{1.5f, 0.31f, BinStatus::kFree}, RopBin{0.0f, 0.45f, BinStatus::kBlind},
                    RopBin{0.0f, 0.0f, BinStatus::kUnobserved}};
  return a;
}

msg::Header Header() {
  msg::Header h;
  h.robot_id = "robot1";
  h.frame_seq = 42;
  return h;
}

TEST(ProfileMessageTest, EveryBinComesBackAsTheServiceInsertedIt) {
  const AnchoredProfile in = Profile();
  const msg::ObstacleProfile m = ProfileToMessage(Header(), in, 1.5f);
  EXPECT_EQ(m.header.frame_seq, 42u);
  EXPECT_EQ(m.experience_id, 7u);
  EXPECT_DOUBLE_EQ(m.offset_theta_rad, 0.2);
  EXPECT_FLOAT_EQ(m.bearing_min_rad, -0.4f);  // the first bin's centre
  // Where the view left the image is what the message says, not the reliable range.
  EXPECT_EQ(m.bins[1].status, msg::ProfileBinStatus::PROFILE_BIN_FREE);
  EXPECT_FLOAT_EQ(m.bins[1].range_m, 0.93f);
  EXPECT_EQ(m.bins[4].status, msg::ProfileBinStatus::PROFILE_BIN_UNOBSERVED);

  const RadialObstacleProfile out = ProfileFromMessage(m);
  EXPECT_NEAR(out.first_bearing_rad, in.profile.first_bearing_rad, 1e-6);
  EXPECT_NEAR(out.bin_width_rad, in.profile.bin_width_rad, 1e-6);
  ASSERT_EQ(out.bins.size(), in.profile.bins.size());
  for (size_t i = 0; i < out.bins.size(); ++i) {
    EXPECT_EQ(out.bins[i].status, in.profile.bins[i].status) << i;
    EXPECT_EQ(out.bins[i].range_m, in.profile.bins[i].range_m) << i;
    EXPECT_EQ(out.bins[i].nearest_visible_m, in.profile.bins[i].nearest_visible_m) << i;
  }

  // A grid built from the messages is the service's grid.
  SensorModelConfig model;
  model.reliable_range_m = 1.5;
  OccupancyGrid from_profile(GridConfig{0.05, 80, 80, -2.0, -2.0}, model);
  OccupancyGrid from_message(GridConfig{0.05, 80, 80, -2.0, -2.0}, model);
  const Pose2D robot{0.3, -0.2, 0.7};
  from_profile.InsertProfile(in.profile, robot);
  from_message.InsertProfile(out, robot);
  EXPECT_EQ(from_message.ToRosCells(), from_profile.ToRosCells());
}

TEST(ProfileMessageTest, TheGridMessageCarriesTheSeenPartOfTheGridInWholeBlocks) {
  SensorModelConfig model;
  model.reliable_range_m = 1.5;
  const GridConfig config{0.025, 1600, 1600, -20.0, -20.0};
  OccupancyGrid grid(config, model);
  msg::OccupancyGrid m = GridToMessage(grid);  // nothing seen: the whole grid
  EXPECT_EQ(m.width, 1600u);
  EXPECT_EQ(m.height, 1600u);
  EXPECT_DOUBLE_EQ(m.origin_x_m, -20.0);

  grid.InsertProfile(Profile().profile, {0.3, -0.2, 0.7});
  grid.InsertProfile(Profile().profile, {-2.9, 1.4, 2.5});
  m = GridToMessage(grid);
  const CellWindow w = GridMessageWindow(grid);
  EXPECT_EQ(w.x0 % kGridMessageBlockCells, 0);
  EXPECT_EQ(w.y0 % kGridMessageBlockCells, 0);
  EXPECT_EQ(w.width % kGridMessageBlockCells, 0);
  EXPECT_LT(m.width * m.height, 1600u * 1600u / 10) << "a small part of the grid";
  ASSERT_EQ(m.cells.size(), size_t{m.width} * m.height);
  EXPECT_DOUBLE_EQ(m.origin_x_m, -20.0 + w.x0 * 0.025);
  EXPECT_DOUBLE_EQ(m.origin_y_m, -20.0 + w.y0 * 0.025);
  // Every cell of the grid is in the message as the whole grid has it, or unknown and at least the
  // margin away from every seen cell.
  const std::vector<int8_t> all = grid.ToRosCells();
  const int margin = static_cast<int>(kGridMessageMarginM / 0.025);
  int seen = 0;
  for (int y = 0; y < 1600; ++y)
    for (int x = 0; x < 1600; ++x) {
      const int8_t v = all[static_cast<size_t>(y) * 1600 + x];
      const bool inside = x >= w.x0 && y >= w.y0 && x < w.x0 + w.width && y < w.y0 + w.height;
      if (inside) {
        ASSERT_EQ(m.cells[static_cast<size_t>(y - w.y0) * m.width + (x - w.x0)], v) << x << "," << y;
      } else {
        ASSERT_EQ(v, -1) << x << "," << y;
      }
      if (v < 0) continue;
      ++seen;
      EXPECT_TRUE(x - margin >= w.x0 && y - margin >= w.y0 && x + margin < w.x0 + w.width &&
                  y + margin < w.y0 + w.height) << x << "," << y;
    }
  EXPECT_GT(seen, 100);

  grid.Clear();
  EXPECT_EQ(GridToMessage(grid).width, 1600u);
}

TEST(ProfileMessageTest, MalformedMessagesAreRefusedNamingTheBin) {
  const msg::ObstacleProfile good = ProfileToMessage(Header(), Profile(), 1.5f);
  auto refused = [](msg::ObstacleProfile m) -> std::string {
    try {
      ProfileFromMessage(m);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  msg::ObstacleProfile m = good;
  m.bins[2].status = static_cast<msg::ProfileBinStatus>(9);
  EXPECT_EQ(refused(m), "bin 2 has an unknown status 9");
  m = good;
  m.bins[0].range_m = -0.1f;
  EXPECT_EQ(refused(m), "bin 0 has a negative or non-finite range");
  m = good;
  m.bins[3].nearest_visible_m = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(refused(m), "bin 3 has a negative or non-finite range");
  m = good;
  m.bearing_step_rad = 0.0f;
  EXPECT_NE(refused(m), "accepted");
  m = good;
  m.max_range_m = std::numeric_limits<float>::infinity();
  EXPECT_NE(refused(m), "accepted");
  EXPECT_EQ(refused(good), "accepted");
}

}  // namespace
}  // namespace rslam::occupancy
