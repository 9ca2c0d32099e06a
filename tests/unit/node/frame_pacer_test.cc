// Lockstep pacing of a frame source (the simulator, the camera service): frames wait for the slowest live stage, never for a stage that
// is gone or never came up.

#include "common/node/frame_pacer.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace rslam {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using Clock = FramePacer::Clock;

TEST(FramePacerTest, FirstFramesInFlightNeedNoReport) {
  FramePacer pacer(2, 2, seconds(2), seconds(10));
  const auto t0 = Clock::time_point{} + seconds(100);
  pacer.Start(t0);
  EXPECT_TRUE(pacer.MayPublish(0, t0));
  EXPECT_TRUE(pacer.MayPublish(1, t0));
  EXPECT_FALSE(pacer.MayPublish(2, t0));
}

TEST(FramePacerTest, WaitsForTheSlowestStage) {
  FramePacer pacer(2, 2, seconds(2), seconds(10));
  const auto t0 = Clock::time_point{} + seconds(100);
  pacer.Start(t0);
  pacer.Report(0, 5, t0);
  pacer.Report(1, 3, t0);
  EXPECT_TRUE(pacer.MayPublish(5, t0));   // needs >= 3 from both
  EXPECT_FALSE(pacer.MayPublish(6, t0));  // stage 1 has only 3
  pacer.Report(1, 4, t0 + milliseconds(1));
  EXPECT_TRUE(pacer.MayPublish(6, t0 + milliseconds(1)));
  EXPECT_EQ(pacer.LastReported(1), 4u);
}

TEST(FramePacerTest, StopsWaitingForASilentStageAndResumesWhenItReports) {
  FramePacer pacer(2, 1, seconds(2), seconds(10));
  const auto t0 = Clock::time_point{} + seconds(100);
  pacer.Start(t0);
  pacer.Report(0, 10, t0);
  pacer.Report(1, 10, t0);
  EXPECT_TRUE(pacer.MayPublish(11, t0));  // one frame in flight
  EXPECT_FALSE(pacer.MayPublish(12, t0 + seconds(1)));
  pacer.Report(0, 11, t0 + seconds(1));
  EXPECT_FALSE(pacer.MayPublish(12, t0 + seconds(1)));  // stage 1 still live, behind
  EXPECT_TRUE(pacer.MayPublish(12, t0 + seconds(3)));   // stage 1 silent for 3 s: gone
  pacer.Report(1, 11, t0 + seconds(4));                 // back (restarted)
  EXPECT_FALSE(pacer.MayPublish(13, t0 + seconds(4)));
}

TEST(FramePacerTest, WaitsForAStageThatNeverReportedOnlyUntilTheStartupTimeout) {
  FramePacer pacer(1, 1, seconds(2), seconds(10));
  const auto t0 = Clock::time_point{} + seconds(100);
  EXPECT_FALSE(pacer.MayPublish(5, t0));  // not started: nothing has gone out yet
  pacer.Start(t0);
  EXPECT_FALSE(pacer.MayPublish(5, t0 + seconds(9)));
  EXPECT_TRUE(pacer.MayPublish(5, t0 + seconds(10)));
}

TEST(FramePacerTest, SaysWhenAFrameGoesOnlyBecauseAStageIsAbsent) {
  FramePacer pacer(2, 1, seconds(2), seconds(10));
  const auto t0 = Clock::time_point{} + seconds(100);
  pacer.Start(t0);
  pacer.Report(0, 10, t0);
  pacer.Report(1, 10, t0);
  EXPECT_FALSE(pacer.PassingAbsentStage(11, t0));  // everyone is there
  EXPECT_TRUE(pacer.PassingAbsentStage(12, t0 + seconds(3)));
  EXPECT_TRUE(pacer.MayPublish(12, t0 + seconds(3)));
}

TEST(FramePacerTest, NoStagesMeansNoWaiting) {
  FramePacer pacer(0, 1, seconds(2), seconds(10));
  pacer.Start(Clock::time_point{});
  EXPECT_TRUE(pacer.MayPublish(1000, Clock::time_point{}));
}

TEST(FramePacerTest, RejectsBadArguments) {
  EXPECT_THROW(FramePacer(1, -1, seconds(1), seconds(1)), std::invalid_argument);
  EXPECT_THROW(FramePacer(1, 0, seconds(1), seconds(1)), std::invalid_argument);
  EXPECT_THROW(FramePacer(1, 1, seconds(-1), seconds(1)), std::invalid_argument);
  FramePacer pacer(1, 1, seconds(1), seconds(1));
  EXPECT_THROW(pacer.Report(1, 0, Clock::time_point{}), std::out_of_range);
  EXPECT_THROW(pacer.Report(-1, 0, Clock::time_point{}), std::out_of_range);
}

}  // namespace
}  // namespace rslam
