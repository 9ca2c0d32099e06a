// DownstreamPacer: the camera's lockstep rule (services/camera/downstream_pacer.h).

#include <gtest/gtest.h>

#include <chrono>

#include "services/camera/downstream_pacer.h"

namespace rslam::camera {
namespace {

using namespace std::chrono_literals;
using Clock = DownstreamPacer::Clock;

TEST(DownstreamPacerTest, FramesWithinTheWindowGoOutAtOnceThenWaitForTheSlowestStage) {
  DownstreamPacer pacer(2, 3, 2s, 5s);
  const Clock::time_point t0{};
  pacer.Start(t0);
  for (uint64_t seq = 0; seq <= 3; ++seq) EXPECT_TRUE(pacer.MayPublish(seq, t0)) << seq;
  EXPECT_FALSE(pacer.MayPublish(4, t0 + 10ms));
  pacer.Report(0, 1, t0 + 20ms);
  EXPECT_FALSE(pacer.MayPublish(4, t0 + 20ms)) << "stage 1 has not reported";
  pacer.Report(1, 1, t0 + 30ms);
  EXPECT_TRUE(pacer.MayPublish(4, t0 + 30ms));
  EXPECT_FALSE(pacer.MayPublish(5, t0 + 30ms));
}

TEST(DownstreamPacerTest, AStageThatNeverReportsIsWaitedForOnlyUntilTheStartupTimeout) {
  DownstreamPacer pacer(1, 0, 2s, 5s);
  const Clock::time_point t0{};
  pacer.Start(t0);
  EXPECT_FALSE(pacer.MayPublish(1, t0 + 4s));
  EXPECT_TRUE(pacer.MayPublish(1, t0 + 5s));
}

TEST(DownstreamPacerTest, AStageThatFallsSilentIsNoLongerWaitedFor) {
  DownstreamPacer pacer(1, 0, 2s, 5s);
  const Clock::time_point t0{};
  pacer.Start(t0);
  pacer.Report(0, 3, t0 + 1s);
  EXPECT_TRUE(pacer.MayPublish(3, t0 + 1s));
  EXPECT_FALSE(pacer.MayPublish(4, t0 + 2s));
  EXPECT_TRUE(pacer.MayPublish(4, t0 + 3s)) << "silent for the stage timeout";
  pacer.Report(0, 2, t0 + 4s);  // an older frame does not move it back
  EXPECT_TRUE(pacer.MayPublish(3, t0 + 4s));
}

TEST(DownstreamPacerTest, BadArgumentsAreRefused) {
  EXPECT_THROW(DownstreamPacer(1, -1, 1s, 1s), std::invalid_argument);
  EXPECT_THROW(DownstreamPacer(1, 1, -1s, 1s), std::invalid_argument);
  DownstreamPacer pacer(1, 1, 1s, 1s);
  EXPECT_THROW(pacer.Report(1, 0, Clock::time_point{}), std::out_of_range);
}

}  // namespace
}  // namespace rslam::camera
