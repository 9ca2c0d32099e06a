// Pins VisualOdometry to paper 000 eqs. 4-7 and OpenRatSLAM's behaviour.
#include "services/odometry/visual_odometry.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

#include "common/config/config_loader.h"
#include "services/odometry/camera_odometry.h"

namespace rslam::odometry {
namespace {

// A smooth random texture (deterministic): coarse noise blown up, like blurred scenery.
cv::Mat Texture(int width, int height, uint64_t seed, int cell = 8) {
  cv::RNG rng(seed);
  cv::Mat coarse(height / cell + 2, width / cell + 2, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 20, 235);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size(width + 2 * cell, height + 2 * cell), 0, 0, cv::INTER_CUBIC);
  return fine(cv::Rect(cell, cell, width, height)).clone();
}

// Frame whose content is `wide` seen from column `offset`: a larger offset moves the scene left.
cv::Mat View(const cv::Mat& wide, int offset, int width) { return wide(cv::Rect(offset, 0, width, wide.rows)).clone(); }

cv::Mat AddNoise(const cv::Mat& grey, double sigma, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat noise(grey.size(), CV_16SC1);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  cv::Mat wide, out;
  grey.convertTo(wide, CV_16SC1);
  wide += noise;
  wide.convertTo(out, CV_8UC1);
  return out;
}

constexpr double kDt = 0.1;
// The default camera_fov_deg (53) over the 640-px test frames: the turn one pixel of shift reads.
constexpr double kRadPerPx = 53.0 * std::numbers::pi / 180.0 / 640.0;

// A 640-px frame whose left and right halves are two textures, each seen from its own offset (a
// smaller one moves it right), so the two halves can shift by different amounts.
class TwoHalves {
 public:
  TwoHalves() : left_(Texture(800, 480, 11)), right_(Texture(800, 480, 12)) {}
  cv::Mat operator()(int left_offset, int right_offset) const {
    cv::Mat out;
    cv::hconcat(View(left_, left_offset, 320), View(right_, right_offset, 320), out);
    return out;
  }

 private:
  const cv::Mat left_, right_;
};

// Turns on the spot read from the two halves, a steady turn followed through one half (turn_continuity_px).
VisualOdometryConfig SteadyTurnConfig(double continuity_px = 3) {
  VisualOdometryConfig config;
  config.rotation_from_halves = true;
  config.subpixel_rotation = true;
  config.turn_in_place_vrot_radps = 0.12;
  config.turn_continuity_px = continuity_px;
  return config;
}

// The turn (px) read from a frame whose halves move `left` and `right` px, after frames turning on
// the spot `turns` px each with both halves alike; `configure` sets the rules under test on top of
// the steady turn (turn_continuity_px 3).
double ShiftAfterTurn(const std::function<void(VisualOdometryConfig&)>& configure, const std::vector<int>& turns,
                      int left, int right) {
  const TwoHalves frame;
  VisualOdometryConfig config = SteadyTurnConfig();
  configure(config);
  VisualOdometry vo(config);
  int offset = 400;
  vo.Update(frame(offset, offset), kDt);
  for (const int turn : turns) {
    offset -= turn;
    EXPECT_NEAR(vo.Update(frame(offset, offset), kDt).vrot * kDt / kRadPerPx, turn, 1.0);
  }
  return vo.Update(frame(offset - left, offset - right), kDt).vrot * kDt / kRadPerPx;
}

TEST(VisualOdometryTest, ShiftedProfileDifferenceIsEq4OnHandComputedArrays) {
  const std::vector<float> previous = {0, 1, 2, 3};
  const std::vector<float> current = {1, 2, 3, 4};
  // s = 0: |1-0| |2-1| |3-2| |4-3| -> 1.
  EXPECT_DOUBLE_EQ(ShiftedProfileDifference(current, previous, 0), 1.0);
  // s = +1: current[n+1] vs previous[n]: |2-0| |3-1| |4-2| -> 2.
  EXPECT_DOUBLE_EQ(ShiftedProfileDifference(current, previous, 1), 2.0);
  // s = -1: current[n] vs previous[n+1]: |1-1| |2-2| |3-3| -> 0.
  EXPECT_DOUBLE_EQ(ShiftedProfileDifference(current, previous, -1), 0.0);
  // s = +3: current[3] vs previous[0]: |4-0| / 1 -> 4.
  EXPECT_DOUBLE_EQ(ShiftedProfileDifference(current, previous, 3), 4.0);
  EXPECT_THROW(ShiftedProfileDifference(current, previous, 4), std::invalid_argument);
}

TEST(VisualOdometryTest, BestShiftIsArgminOfEq4AndPrefersNoMotionOnTies) {
  const std::vector<float> previous = {0, 1, 2, 3, 0, 0};
  const std::vector<float> moved_right = {9, 0, 1, 2, 3, 0};
  const ProfileMatch m = BestProfileShift(moved_right, previous, 2, 1);
  EXPECT_EQ(m.shift, 1);
  EXPECT_DOUBLE_EQ(m.difference, 0.0);
  const std::vector<float> flat(6, 0.5f);
  EXPECT_EQ(BestProfileShift(flat, flat, 3, 1).shift, 0);
  // The overlap rule (|s| < w - min_overlap) stops the search before max_shift.
  const std::vector<float> ramp = {0, 1, 2, 3, 4, 5, 6, 7};
  const std::vector<float> far_right = {9, 9, 9, 9, 9, 9, 0, 1};  // ramp moved right by 6
  EXPECT_EQ(BestProfileShift(far_right, ramp, 7, 1).shift, 6);      // overlap 2 > 1
  EXPECT_NE(BestProfileShift(far_right, ramp, 7, 2).shift, 6);      // overlap 2 is not > 2
}

// The search abandons a shift once it cannot beat the best so far; it must still return the
// exhaustive argmin (first of equal values in search order) and that shift's exact f(s).
TEST(VisualOdometryTest, BestShiftEqualsTheExhaustiveSearchOnRandomProfiles) {
  cv::RNG rng(17);
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 40 + trial * 7;
    std::vector<float> previous(w), current(w);
    for (float& v : previous) v = static_cast<float>(rng.uniform(0.0, 1.0));
    const int moved = trial % 9 - 4;
    for (int n = 0; n < w; ++n) {
      const int source = std::clamp(n - moved, 0, w - 1);
      current[n] = previous[source] * 1.1f + static_cast<float>(rng.uniform(-0.02, 0.02));
    }
    for (const bool gain : {false, true}) {
      const int max_shift = 20, min_overlap = 10;
      ProfileMatch expected{0, ShiftedProfileDifference(current, previous, 0, gain)};
      for (int m = 1; m <= max_shift && w - m > min_overlap; ++m) {
        for (int s : {m, -m}) {
          const double f = ShiftedProfileDifference(current, previous, s, gain);
          if (f < expected.difference) expected = {s, f};
        }
      }
      const ProfileMatch got = BestProfileShift(current, previous, max_shift, min_overlap, gain);
      EXPECT_EQ(got.shift, expected.shift) << "trial " << trial << " gain " << gain;
      EXPECT_EQ(got.difference, expected.difference) << "trial " << trial << " gain " << gain;
    }
  }
}

TEST(VisualOdometryTest, GainMatchingRemovesAnExposureChange) {
  const std::vector<float> previous = {0.2f, 0.4f, 0.3f, 0.5f};
  const std::vector<float> brighter = {0.3f, 0.6f, 0.45f, 0.75f};  // x 1.5
  EXPECT_NEAR(ShiftedProfileDifference(brighter, previous, 0), (0.1 + 0.2 + 0.15 + 0.25) / 4, 1e-6);
  EXPECT_NEAR(ShiftedProfileDifference(brighter, previous, 0, true), 0.0, 1e-6);
}

TEST(VisualOdometryTest, FirstFrameReturnsZero) {
  VisualOdometry vo(VisualOdometryConfig{});
  const Velocity v = vo.Update(Texture(640, 480, 1), kDt);
  EXPECT_EQ(v.vtrans, 0.0);
  EXPECT_EQ(v.vrot, 0.0);
}

TEST(VisualOdometryTest, SceneMovingRightIsCounterClockwiseRotationOfExpectedMagnitude) {
  const cv::Mat wide = Texture(760, 480, 2);
  for (int shift : {12, -12, 25}) {
    VisualOdometry vo(VisualOdometryConfig{});
    vo.Update(View(wide, 60, 640), kDt);
    // Content moved right by `shift` pixels: the camera turned left (counter-clockwise).
    const Velocity v = vo.Update(View(wide, 60 - shift, 640), kDt);
    EXPECT_EQ(v.rotation_shift_px, shift);
    const double expected = shift * (53.0 * std::numbers::pi / 180.0) / 640.0 / kDt;
    EXPECT_NEAR(v.vrot, expected, 1e-9) << "shift " << shift;
    // A pure rotation leaves the best-shift difference (eq. 6) small.
    EXPECT_LT(v.vtrans, 0.5);
  }
}

TEST(VisualOdometryTest, TurnContinuityKeepsASteadyTurnWhereOneHalfMismatches) {
  const TwoHalves frame;
  // Turning on the spot 20 px a frame (0.29 rad/s); in the last frame the right half matches
  // 10 px the other way (a stretch of wall that repeats), and the halves share no shift.
  const auto last_turn = [&](double continuity_px, int turning_frames) {
    VisualOdometryConfig config = SteadyTurnConfig(continuity_px);
    VisualOdometry vo(config);
    int offset = 400;
    vo.Update(frame(offset, offset), kDt);
    for (int i = 0; i < turning_frames; ++i) {
      offset -= 20;
      const Velocity turning = vo.Update(frame(offset, offset), kDt);
      EXPECT_NEAR(turning.vrot * kDt / kRadPerPx, 20.0, 0.2);
    }
    return vo.Update(frame(offset - 20, offset + 10), kDt).vrot * kDt / kRadPerPx;
  };
  EXPECT_NEAR(last_turn(0.0, 2), 0.0, 1e-9);   // off: the shared shift, none
  EXPECT_NEAR(last_turn(3.0, 2), 20.0, 0.5);   // the half that goes on turning as before
  EXPECT_NEAR(last_turn(3.0, 1), 0.0, 1e-9);   // one turning frame is not yet a steady turn
  VisualOdometryConfig negative;
  negative.turn_continuity_px = -1;
  EXPECT_THROW(negative.Validate(), ConfigError);
}

// Driving at a wall obliquely, the near half's view streams outwards a few pixels a frame while
// the other half's mismatches: read as a slow turn twice, the steady turn above then followed that
// half as the turn going on. With turn_continuity_forward_px, halves both moving as a forward
// drive moves them (the left half left, the right half right), both slower than it, are no turn.
TEST(VisualOdometryTest, ASteadyTurnIsNotFollowedThroughHalvesMovingAsAForwardDriveMovesThem) {
  // Two frames turning clockwise `turn` px each, then the left half moves on at the turn's rate and
  // the right half `right` px.
  const auto after_turn = [](double forward_px, int turn, int right) {
    return ShiftAfterTurn([&](VisualOdometryConfig& c) { c.turn_continuity_forward_px = forward_px; }, {turn, turn},
                          turn, right);
  };
  EXPECT_NEAR(after_turn(0, -10, 4), -10.0, 1.0);  // off: the left half goes on as the turn
  EXPECT_NEAR(after_turn(16, -10, 4), 0.0, 1e-9);  // both halves as a drive moves them
  EXPECT_NEAR(after_turn(16, -20, 4), -20.0, 1.0);  // faster than a drive moves a half: the turn
  EXPECT_NEAR(after_turn(16, -10, 20), -10.0, 1.0);  // the right half mismatched past it
  EXPECT_NEAR(after_turn(16, -10, -4), -10.0, 1.0);  // not the pattern of a drive
  VisualOdometryConfig negative;
  negative.turn_continuity_forward_px = -1;
  EXPECT_THROW(negative.Validate(), ConfigError);
}

TEST(VisualOdometryTest, TurnFollowKeepsATurnsSecondFrameWhereOneHalfMismatches) {
  // Frames of a turn on the spot, both halves `turns` px each; then the halves move by `left` and
  // `right` px and share no shift (in front of a plain wall, where a turn starts).
  const auto after_turn = [](double follow_px, std::vector<int> turns, int left, int right) {
    return ShiftAfterTurn([&](VisualOdometryConfig& c) { c.turn_follow_px = follow_px; }, turns, left, right);
  };
  // Turning left: the left half goes on (2 px faster), the right half mismatches 10 px the other way.
  EXPECT_NEAR(after_turn(0, {20}, 22, -10), 0.0, 1e-9);  // off: the shared shift, none
  EXPECT_NEAR(after_turn(8, {20}, 22, -10), 22.0, 1.0);
  EXPECT_NEAR(after_turn(8, {20}, 30, -10), 0.0, 1e-9);  // 10 px off the turn: not followed
  // Turning right, mirrored: the right half goes on.
  EXPECT_NEAR(after_turn(8, {-20}, 10, -22), -22.0, 1.0);
  // A half moving the way driving forward moves it (the left half left, the right half right) is
  // not followed, however near the turn's shift: the robot driving on at a wall after the turn.
  EXPECT_NEAR(after_turn(8, {20}, -5, 18), 0.0, 1e-9);
  EXPECT_NEAR(after_turn(8, {-20}, -18, 5), 0.0, 1e-9);
  // Without a turn before it, such a frame is no turn.
  EXPECT_NEAR(after_turn(8, {0}, 22, -10), 0.0, 1e-9);
  // A turn that jumped from the frame before (a turn's slower last frame, then a misread one) is
  // not followed; one that went on at its rate is.
  EXPECT_NEAR(after_turn(8, {10, 30}, 30, -10), 0.0, 1e-9);
  EXPECT_NEAR(after_turn(8, {24, 30}, 30, -10), 30.0, 1.0);
  VisualOdometryConfig negative;
  negative.turn_follow_px = -1;
  negative.rotation_from_halves = true;
  EXPECT_THROW(negative.Validate(), ConfigError);
  VisualOdometryConfig whole;
  whole.turn_follow_px = 8;  // without rotation_from_halves
  try {
    whole.Validate();
    FAIL() << "accepted turn_follow_px without halves";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "turn_follow_px");
  }
}

TEST(VisualOdometryTest, AMatchAtTheSearchsEdgeReadsNoTurnWhenConfigured) {
  const TwoHalves frame;
  // Both halves' views move by `shift` px; 40 px is the edge of the search (max_shift_px 40).
  const auto read = [&](bool halves, bool edge_reads_no_turn, int shift) {
    VisualOdometryConfig config;
    config.rotation_from_halves = halves;
    config.edge_shift_reads_no_turn = edge_reads_no_turn;
    VisualOdometry vo(config);
    vo.Update(frame(400, 400), kDt);
    return vo.Update(frame(400 - shift, 400 - shift), kDt).vrot * kDt / kRadPerPx;
  };
  for (const bool halves : {false, true}) {
    EXPECT_NEAR(read(halves, false, 39), 39.0, 1e-9) << "halves " << halves;
    EXPECT_NEAR(read(halves, true, 39), 39.0, 1e-9) << "halves " << halves;
    EXPECT_NEAR(read(halves, false, 40), 40.0, 1e-9) << "halves " << halves;
    EXPECT_NEAR(read(halves, true, 40), 0.0, 1e-9) << "halves " << halves;
    EXPECT_NEAR(read(halves, true, -40), 0.0, 1e-9) << "halves " << halves;
  }
}

TEST(VisualOdometryTest, AgreedRateKeepsATurnWhoseHalvesAgreedUntilOneMismatches) {
  const TwoHalves frame;
  VisualOdometryConfig config = SteadyTurnConfig();
  // One frame of a turn, 20 px, both halves agreeing; then the right half matches 10 px the other
  // way. One turning frame is no steady turn yet (turn_continuity_px alone reads no turn), but
  // its halves agreed on the rate, and the left half goes on at it.
  const auto after_mismatch = [&](bool agreed_rate, bool stop_between) {
    config.turn_continuity_agreed_rate = agreed_rate;
    VisualOdometry vo(config);
    vo.Update(frame(400, 400), kDt);
    EXPECT_NEAR(vo.Update(frame(380, 380), kDt).vrot * kDt / kRadPerPx, 20.0, 0.2);
    if (stop_between) {
      EXPECT_NEAR(vo.Update(frame(380, 380), kDt).vrot * kDt / kRadPerPx, 0.0, 0.1);
    }
    return vo.Update(frame(360, 390), kDt).vrot * kDt / kRadPerPx;
  };
  EXPECT_NEAR(after_mismatch(false, false), 0.0, 1e-9);
  EXPECT_NEAR(after_mismatch(true, false), 20.0, 1.0);
  // A frame that is no turn on the spot ends the turn and its rate.
  EXPECT_NEAR(after_mismatch(true, true), 0.0, 1e-9);
  // So do halves agreeing on a slower turn (a turn's last, partial frame): driving on after it,
  // the right half's 9 px is not taken for a turn going on at 10.
  config.turn_continuity_agreed_rate = true;
  VisualOdometry vo(config);
  vo.Update(frame(400, 400), kDt);
  vo.Update(frame(380, 380), kDt);
  EXPECT_NEAR(vo.Update(frame(370, 370), kDt).vrot * kDt / kRadPerPx, 10.0, 0.2);
  EXPECT_NEAR(vo.Update(frame(374, 361), kDt).vrot, 0.0, 1e-9);
}

TEST(VisualOdometryTest, SmoothedRotationProfileKeepsTheTurn) {
  const cv::Mat wide = Texture(760, 480, 2);
  for (const int smoothing : {0, 2, 8}) {
    VisualOdometryConfig config;
    config.subpixel_rotation = true;
    config.rotation_profile_smoothing_px = smoothing;
    VisualOdometry vo(config);
    vo.Update(View(wide, 60, 640), kDt);
    for (int shift : {12, -25}) {
      const Velocity v = vo.Update(View(wide, 60 - shift, 640), kDt);
      EXPECT_NEAR(v.vrot * kDt / kRadPerPx, shift, 0.2) << "smoothing " << smoothing;
      vo.Update(View(wide, 60, 640), kDt);  // back
    }
  }
}

TEST(VisualOdometryTest, SubpixelRotationRecoversAFractionalShift) {
  // The scene moved right by 12.4 px: the view of a 5x wider texture resampled at 1/5 pixel.
  const cv::Mat wide = Texture(5 * 760, 480, 3, 40);
  auto view = [&](int offset_fifths) {
    cv::Mat small;
    cv::resize(wide(cv::Rect(offset_fifths, 0, 5 * 640, 480)), small, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
    return small;
  };
  for (const bool subpixel : {false, true}) {
    VisualOdometryConfig config;
    config.subpixel_rotation = subpixel;
    VisualOdometry vo(config);
    vo.Update(view(300), kDt);
    const Velocity v = vo.Update(view(300 - 62), kDt);
    EXPECT_EQ(v.rotation_shift_px, 12);
    EXPECT_NEAR(v.vrot * kDt / kRadPerPx, subpixel ? 12.4 : 12.0, subpixel ? 0.1 : 1e-9);
  }
}

TEST(VisualOdometryTest, RotationFromHalvesKeepsATurnAndIgnoresFlowOnlyOneHalfShows) {
  VisualOdometryConfig halves;
  halves.rotation_from_halves = true;
  halves.subpixel_rotation = true;
  VisualOdometryConfig whole = halves;
  whole.rotation_from_halves = false;
  // A turn moves both halves the same way, by the same shift: that shift is the turn.
  const cv::Mat wide = Texture(760, 480, 2);
  for (int shift : {12, -25}) {
    VisualOdometry vo(halves);
    vo.Update(View(wide, 60, 640), kDt);
    const Velocity v = vo.Update(View(wide, 60 - shift, 640), kDt);
    EXPECT_EQ(v.rotation_shift_px, shift);
    EXPECT_NEAR(v.vrot * kDt / kRadPerPx, shift, 0.2);
  }
  // Driving straight at a wall whose left half has the stronger texture: the view grows 10%
  // about the centre, the left half moving left and the right half right. One match follows the
  // left half and reads a clockwise turn of several pixels; the halves' mean reads none.
  cv::Mat scene = Texture(640, 480, 5);
  cv::Mat right = scene(cv::Rect(320, 0, 320, 480));
  right.convertTo(right, -1, 0.2, 100);
  const cv::Size size = scene.size();
  const int w = static_cast<int>(std::lround(640 / 1.1)), h = static_cast<int>(std::lround(480 / 1.1));
  cv::Mat nearer;
  cv::resize(scene(cv::Rect((640 - w) / 2, (480 - h) / 2, w, h)), nearer, size, 0, 0, cv::INTER_LINEAR);
  VisualOdometry one(whole), two(halves);
  one.Update(scene, kDt);
  two.Update(scene, kDt);
  EXPECT_LT(one.Update(nearer, kDt).vrot * kDt / kRadPerPx, -4.0);
  EXPECT_NEAR(two.Update(nearer, kDt).vrot * kDt / kRadPerPx, 0.0, 0.05);
  // A frame of two 320-px views side by side.
  const auto side_by_side = [](const cv::Mat& left, const cv::Mat& right) {
    cv::Mat frame;
    cv::hconcat(left, right, frame);
    return frame;
  };
  // Driving past a wall close on the left: its texture streams 14 px left while the far right
  // half holds still. The halves' mean would read a 7-px turn; they share none.
  const cv::Mat near_wall = Texture(680, 480, 7);
  const cv::Mat far_wall = Texture(360, 480, 8);
  VisualOdometry driving(halves);
  driving.Update(side_by_side(View(near_wall, 20, 320), View(far_wall, 20, 320)), kDt);
  EXPECT_NEAR(driving.Update(side_by_side(View(near_wall, 34, 320), View(far_wall, 20, 320)), kDt).vrot * kDt /
                  kRadPerPx,
              0.0, 0.05);
  // Turning while the near wall streams faster: both halves move the same way (12 and 5 px), the
  // turn is the smaller shift.
  VisualOdometry arc(halves);
  arc.Update(side_by_side(View(near_wall, 20, 320), View(far_wall, 25, 320)), kDt);
  EXPECT_NEAR(arc.Update(side_by_side(View(near_wall, 8, 320), View(far_wall, 20, 320)), kDt).vrot * kDt / kRadPerPx,
              5.0, 0.2);
  // Each half must be wider than min_overlap_px.
  halves.vrot_image_x_min = 300;
  halves.vrot_image_x_max = 350;
  VisualOdometry narrow(halves);
  try {
    narrow.Update(scene, kDt);
    FAIL() << "accepted halves narrower than min_overlap_px";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("half the rotation crop"), std::string::npos) << e.what();
  }
}

TEST(VisualOdometryTest, RotationRateScalesWithDt) {
  const cv::Mat wide = Texture(760, 480, 3);
  VisualOdometry a(VisualOdometryConfig{}), b(VisualOdometryConfig{});
  a.Update(View(wide, 60, 640), 0.1);
  b.Update(View(wide, 60, 640), 0.1);
  const double fast = a.Update(View(wide, 50, 640), 0.1).vrot;
  const double slow = b.Update(View(wide, 50, 640), 0.2).vrot;
  EXPECT_GT(fast, 0.0);
  EXPECT_NEAR(slow, fast / 2.0, 1e-12);
}

// The azimuth pixel (u, v) of a 320 x 240 pinhole image over 60 degrees looks along, tilted down
// by tilt (right of the axis positive), as MakeEqualAngleColumns models it.
double PixelAzimuth(double u, int v, double tilt) {
  const double focal = 160.0 / std::tan(std::numbers::pi / 6.0);
  const double x = (u + 0.5 - 160.0) / focal, y = (v + 0.5 - 120.0) / focal;
  return std::atan(x / (std::cos(tilt) - y * std::sin(tilt)));
}

TEST(VisualOdometryTest, EqualAngleColumnsLieAtEqualAzimuthsInEveryRowOfTheCrop) {
  const double fov = std::numbers::pi / 3.0;
  for (const double tilt : {0.0, 0.3}) {
    for (const cv::Rect& crop : {cv::Rect(0, 0, 320, 90), cv::Rect(100, 30, 120, 40), cv::Rect(0, 200, 160, 40)}) {
      const EqualAngleColumns columns = MakeEqualAngleColumns({320, 240}, fov, tilt, crop);
      ASSERT_EQ(columns.count, crop.width);
      ASSERT_EQ(columns.at_px.size(), static_cast<size_t>(crop.width * crop.height));
      const double first = PixelAzimuth(crop.x + columns.at_px[0], crop.y, tilt);
      for (int r = 0; r < crop.height; r += 7) {
        for (int j = 0; j < crop.width; j += 13) {
          const double at = columns.at_px[static_cast<size_t>(r * crop.width + j)];
          EXPECT_GE(at, 0.0);
          EXPECT_LE(at, crop.width - 1.0);
          EXPECT_NEAR(PixelAzimuth(crop.x + at, crop.y + r, tilt), first + j * columns.rad_per_column, 1e-9)
              << tilt << " " << r << " " << j;
        }
      }
    }
  }
  const EqualAngleColumns level = MakeEqualAngleColumns({320, 240}, fov, 0.0, {0, 0, 320, 240});
  EXPECT_LT(level.at_px[161] - level.at_px[160], 0.95);  // a centre column spans more than a pixel's
  EXPECT_GT(level.at_px[1] - level.at_px[0], 1.15);      // ... average angle, an edge column less
  EXPECT_THROW(MakeEqualAngleColumns({320, 240}, std::numbers::pi, 0.0, {0, 0, 320, 90}), std::invalid_argument);
  EXPECT_THROW(MakeEqualAngleColumns({320, 240}, fov, 0.0, {300, 0, 40, 90}), std::invalid_argument);
}

TEST(VisualOdometryTest, EqualAngleProfileInterpolatesEachRowAndAveragesThem) {
  cv::Mat crop(2, 3, CV_8UC1);
  crop.at<uint8_t>(0, 0) = 0, crop.at<uint8_t>(0, 1) = 51, crop.at<uint8_t>(0, 2) = 153;
  crop.at<uint8_t>(1, 0) = 255, crop.at<uint8_t>(1, 1) = 255, crop.at<uint8_t>(1, 2) = 255;
  EqualAngleColumns columns;
  columns.count = 3;
  columns.at_px = {0.0, 0.5, 2.0, 0.0, 1.25, 2.0};
  std::vector<float> profile;
  EqualAngleProfile(crop, columns, profile);
  ASSERT_EQ(profile.size(), 3u);
  EXPECT_NEAR(profile[0], 0.5, 1e-6);                  // (0 + 255) / 2 / 255
  EXPECT_NEAR(profile[1], (25.5 + 255.0) / 510.0, 1e-6);
  EXPECT_NEAR(profile[2], (153.0 + 255.0) / 510.0, 1e-6);
  EXPECT_THROW(EqualAngleProfile(crop(cv::Rect(0, 0, 2, 2)), columns, profile), std::invalid_argument);
}

// A 320 x 240 pinhole camera over 60 degrees, tilted down by `tilt`, turning left on the spot
// before scenery textured by bearing only within `band` (bearings in the first frame, rad, left
// of the robot positive) and plain grey elsewhere; the rotation crop is the top 90 rows, as in the
// demo. Returns the turn read, rad, by the visual odometry told the tilt, or with
// through_camera_odometry by the odometry service's CameraOdometry told it by the floor camera.
double PinholeTurnRead(bool equal_angle, double tilt, std::pair<double, double> band, double turn,
                       bool through_camera_odometry = false) {
  const cv::Mat texture = Texture(2400, 8, 21, 12);  // bearings -1.2..1.2 rad, 1 mrad a column
  auto frame = [&](double heading) {
    cv::Mat image(240, 320, CV_8UC1);
    for (int v = 0; v < 240; ++v) {
      for (int u = 0; u < 320; ++u) {
        const double bearing = heading - PixelAzimuth(u, v, tilt);
        const double x = (bearing + 1.2) * 1000.0;
        const int i = std::clamp(static_cast<int>(x), 0, 2398);
        const double t = std::clamp(x - i, 0.0, 1.0);
        const double textured = (1 - t) * texture.at<uint8_t>(4, i) + t * texture.at<uint8_t>(4, i + 1);
        image.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(bearing >= band.first && bearing <= band.second ? textured : 128.0);
      }
    }
    return image;
  };
  VisualOdometryConfig cfg;
  cfg.camera_fov_deg = 60.0;
  if (!through_camera_odometry) cfg.camera_tilt_rad = tilt;
  cfg.vrot_image_x_min = 0;
  cfg.vrot_image_x_max = -1;
  cfg.vrot_image_y_min = 0;
  cfg.vrot_image_y_max = 90;
  cfg.vtrans_image_x_min = 110;
  cfg.vtrans_image_x_max = 210;
  cfg.vtrans_image_y_min = 20;
  cfg.vtrans_image_y_max = 110;
  cfg.subpixel_rotation = true;
  cfg.equal_angle_columns = equal_angle;
  if (through_camera_odometry) {
    FloorOdometryNodeConfig floor;  // off: only its camera is read
    floor.boundary.camera.tilt_rad = tilt;
    CameraOdometry odometry(cfg, floor);
    odometry.Update(frame(0.0), kDt);
    return odometry.Update(frame(turn), kDt).velocity.vrot * kDt;
  }
  VisualOdometry vo(cfg);
  vo.Update(frame(0.0), kDt);
  return vo.Update(frame(turn), kDt).vrot * kDt;
}

TEST(VisualOdometryTest, EqualAngleColumnsReadATurnAlikeWhereverTheTextureLies) {
  // The same turn (0.06 rad, about 17 px at the centre, 22 px at the edges) before texture near the
  // image's centre and near its left edge, the camera level and tilted as the demo's.
  const double turn = 0.06;
  const std::pair<double, double> centre{-0.25, 0.25}, edge{0.28, 0.6};
  for (const double tilt : {0.0, 0.3}) {
    EXPECT_LT(PinholeTurnRead(false, tilt, centre, turn), 0.96 * turn) << tilt;  // pixel columns: short at the centre
    EXPECT_GT(PinholeTurnRead(false, tilt, edge, turn), 1.03 * turn) << tilt;    // ... long toward the edge
    EXPECT_NEAR(PinholeTurnRead(true, tilt, centre, turn), turn, 0.01 * turn) << tilt;
    EXPECT_NEAR(PinholeTurnRead(true, tilt, edge, turn), turn, 0.01 * turn) << tilt;
  }
  // The odometry service's config gives the camera's tilt once, in floor_odometry.camera.
  const double tilted = PinholeTurnRead(true, 0.3, edge, turn);
  EXPECT_NE(tilted, PinholeTurnRead(true, 0.0, edge, turn));
  EXPECT_EQ(PinholeTurnRead(true, 0.3, edge, turn, true), tilted);
}

TEST(VisualOdometryTest, StandstillGivesZeroSpeedWithIdenticalAndNoisyFrames) {
  const cv::Mat scene = Texture(640, 480, 4);
  VisualOdometry vo(VisualOdometryConfig{});
  vo.Update(scene, kDt);
  const Velocity same = vo.Update(scene, kDt);
  EXPECT_EQ(same.vtrans, 0.0);
  EXPECT_EQ(same.vrot, 0.0);
  double worst_speed = 0.0, worst_rotation = 0.0;
  for (int i = 0; i < 20; ++i) {
    const Velocity v = vo.Update(AddNoise(scene, 3.0, 100 + i), kDt);
    worst_speed = std::max(worst_speed, v.vtrans);
    worst_rotation = std::max(worst_rotation, std::abs(v.vrot));
  }
  EXPECT_LT(worst_speed, 0.05);
  EXPECT_EQ(worst_rotation, 0.0);

  // Without the noise floor the same noise reads as motion (the OpenRatSLAM standstill drift).
  VisualOdometryConfig no_floor;
  no_floor.vtrans_noise_floor = 0.0;
  VisualOdometry drifting(no_floor);
  drifting.Update(scene, kDt);
  EXPECT_GT(drifting.Update(AddNoise(scene, 3.0, 7), kDt).vtrans, 0.1);
}

TEST(VisualOdometryTest, BrightnessChangeAloneDoesNotReadAsSpeed) {
  const cv::Mat scene = Texture(640, 480, 5);
  cv::Mat brighter, darker;
  scene.convertTo(brighter, CV_8UC1, 1.15);
  scene.convertTo(darker, CV_8UC1, 0.8);
  VisualOdometry vo(VisualOdometryConfig{});
  vo.Update(scene, kDt);
  EXPECT_LT(vo.Update(brighter, kDt).vtrans, 0.5);
  EXPECT_LT(vo.Update(darker, kDt).vtrans, 0.5);

  VisualOdometryConfig raw;
  raw.normalise_profile_brightness = false;
  VisualOdometry unnormalised(raw);
  unnormalised.Update(scene, kDt);
  EXPECT_GT(unnormalised.Update(brighter, kDt).vtrans, 5.0);
}

TEST(VisualOdometryTest, ForwardMotionGivesClampedPositiveSpeed) {
  const cv::Mat scene = Texture(640, 480, 6);
  cv::Mat zoomed;
  cv::resize(scene(cv::Rect(16, 12, 608, 456)), zoomed, scene.size(), 0, 0, cv::INTER_LINEAR);
  VisualOdometry vo(VisualOdometryConfig{});
  vo.Update(scene, kDt);
  const Velocity v = vo.Update(zoomed, kDt);
  EXPECT_GT(v.vtrans, 1.0);
  EXPECT_LE(v.vtrans, VisualOdometryConfig{}.vtrans_max);
  // At the nominal rate vtrans is OpenRatSLAM's min((v - floor) * scaling, max).
  const VisualOdometryConfig c;
  EXPECT_NEAR(v.vtrans, std::min((v.speed_difference - c.vtrans_noise_floor) * c.vtrans_scaling, c.vtrans_max), 1e-9);
}

TEST(VisualOdometryTest, TurningOnTheSpotReadsAsNoForwardMotionWhenConfigured) {
  // A turn whose view also changes (noise stands in for perspective) reads as some speed...
  const cv::Mat wide = Texture(760, 480, 4);
  const cv::Mat before = View(wide, 60, 640);
  const cv::Mat after = AddNoise(View(wide, 40, 640), 12.0, 5);
  VisualOdometry plain(VisualOdometryConfig{});
  plain.Update(before, kDt);
  const Velocity turning = plain.Update(after, kDt);
  ASSERT_EQ(turning.rotation_shift_px, 20);
  ASSERT_GT(turning.vtrans, 0.0);
  // ... which a turn-in-place robot's config removes at or above the threshold, and only there.
  VisualOdometryConfig config;
  config.turn_in_place_vrot_radps = std::abs(turning.vrot);
  VisualOdometry robot(config);
  robot.Update(before, kDt);
  EXPECT_EQ(robot.Update(after, kDt).vtrans, 0.0);
  config.turn_in_place_vrot_radps = std::abs(turning.vrot) * 1.01;
  VisualOdometry below(config);
  below.Update(before, kDt);
  EXPECT_DOUBLE_EQ(below.Update(after, kDt).vtrans, turning.vtrans);
}

// Colour frames are converted crop by crop; the velocities must be those of the whole frame
// converted to grey first (as the services and `rslam run` do).
TEST(VisualOdometryTest, ColourFramesGiveTheVelocitiesOfTheirGreyConversion) {
  cv::RNG rng(23);
  cv::Mat coarse(62, 102, CV_8UC3);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 256);
  cv::Mat wide;
  cv::resize(coarse, wide, cv::Size(816, 496), 0, 0, cv::INTER_CUBIC);
  for (const int code : {-1, static_cast<int>(cv::COLOR_BGR2BGRA)}) {
    VisualOdometry colour(VisualOdometryConfig{}), grey(VisualOdometryConfig{});
    for (int i = 0; i < 12; ++i) {
      cv::Mat frame = wide(cv::Rect(8 * i + (i % 3), 8 + i % 5, 640, 480)).clone();
      if (code >= 0) cv::cvtColor(frame, frame, code);
      cv::Mat converted;
      cv::cvtColor(frame, converted, frame.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
      const Velocity a = colour.Update(frame, kDt);
      const Velocity b = grey.Update(converted, kDt);
      EXPECT_EQ(a.rotation_shift_px, b.rotation_shift_px) << i;
      EXPECT_EQ(a.vrot, b.vrot) << i;
      EXPECT_EQ(a.vtrans, b.vtrans) << i;
      EXPECT_EQ(a.speed_difference, b.speed_difference) << i;
    }
  }
}

TEST(VisualOdometryTest, RejectsBadImagesAndDt) {
  VisualOdometry vo(VisualOdometryConfig{});
  EXPECT_THROW(vo.Update(cv::Mat(), kDt), std::invalid_argument);
  EXPECT_THROW(vo.Update(cv::Mat(480, 640, CV_32FC1, cv::Scalar::all(0)), kDt), std::invalid_argument);
  EXPECT_THROW(vo.Update(cv::Mat(480, 640, CV_8UC2, cv::Scalar::all(0)), kDt), std::invalid_argument);
  EXPECT_THROW(vo.Update(cv::Mat(100, 100, CV_8UC1, cv::Scalar(0)), kDt), std::invalid_argument);  // crop outside
  const cv::Mat scene = Texture(640, 480, 7);
  for (double dt : {0.0, -0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(vo.Update(scene, dt), std::invalid_argument) << dt;
  }
  vo.Update(scene, kDt);
  EXPECT_THROW(vo.Update(Texture(800, 600, 7), kDt), std::invalid_argument);  // size change
  EXPECT_NO_THROW(vo.Update(scene, kDt));  // the bad frame left the state usable
  vo.Reset();
  EXPECT_NO_THROW(vo.Update(Texture(800, 600, 7), kDt));
}

TEST(VisualOdometryTest, RejectsBadConfigNamingTheKey) {
  VisualOdometryConfig c;
  c.vtrans_image_x_max = 100;  // < x_min
  try {
    VisualOdometry vo(c);
    FAIL() << "accepted a bad crop";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "vtrans_image_x_max");
  }
  VisualOdometryConfig fov;
  fov.camera_fov_deg = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(VisualOdometry{fov}, ConfigError);
  VisualOdometryConfig agreed;
  agreed.turn_continuity_agreed_rate = true;  // without rotation_from_halves and turn_continuity_px
  try {
    VisualOdometry vo(agreed);
    FAIL() << "accepted turn_continuity_agreed_rate without halves";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "turn_continuity_agreed_rate");
  }
  for (const int smoothing : {-1, 65}) {
    VisualOdometryConfig smooth;
    smooth.rotation_profile_smoothing_px = smoothing;
    try {
      VisualOdometry vo(smooth);
      FAIL() << "accepted rotation_profile_smoothing_px " << smoothing;
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.key(), "rotation_profile_smoothing_px");
    }
  }
}

TEST(VisualOdometryTest, TheFloorCameraAndTheColumnProfilesAreOneCamera) {
  OdometryNodeConfig config;
  LoadConfigSection(LoadYamlFile(std::string(RSLAM_SOURCE_DIR) + "/deploy/config/demo.yaml"), "odometry", config);
  ASSERT_TRUE(config.floor.enabled);
  EXPECT_NEAR(config.floor.boundary.camera.HorizontalFovDeg(), config.visual.camera_fov_deg, 1e-3);
  // A field of view that is not the floor camera's (the default 53 degrees of St Lucia's camera).
  config.visual.camera_fov_deg = 53.0;
  try {
    config.Validate();
    FAIL() << "accepted a camera_fov_deg 7 degrees off the floor camera's";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "camera_fov_deg");
    EXPECT_NE(std::string(e.what()).find("60.00 degrees"), std::string::npos) << e.what();
  }
  config.visual.camera_fov_deg = 60.4;
  EXPECT_NO_THROW(config.Validate());
  // Without the floor odometry the column profiles' field of view is their own (the dataset presets).
  config.visual.camera_fov_deg = 53.0;
  config.floor.enabled = false;
  EXPECT_NO_THROW(config.Validate());
}

TEST(VisualOdometryTest, IratFramesRunWithThePreset) {
  const char* data = std::getenv("RSLAM_SHARED_DATA");
  if (!data || !std::filesystem::exists(std::filesystem::path(data) / "irat")) GTEST_SKIP() << "no shared data";
  VisualOdometryConfig config;
  LoadConfigSection(LoadYamlFile(std::string(RSLAM_SOURCE_DIR) + "/deploy/presets/irat.yaml"), "odometry", config);
  VisualOdometry vo(config);
  int frames = 0;
  for (int i = 33; i <= 37; ++i) {
    const cv::Mat grey = cv::imread(std::string(data) + "/irat/test_A_batch_0000" + std::to_string(i) + ".png",
                                    cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(grey.empty());
    const Velocity v = vo.Update(grey, 0.1);
    EXPECT_TRUE(std::isfinite(v.vtrans) && std::isfinite(v.vrot));
    EXPECT_GE(v.vtrans, 0.0);
    EXPECT_LE(v.vtrans, config.vtrans_max);
    ++frames;
  }
  EXPECT_EQ(frames, 5);
}

}  // namespace
}  // namespace rslam::odometry
