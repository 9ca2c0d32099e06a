// The deadline that bounds a service's stop (saving its state, leaving the bus): it ends a process
// that hangs past it, and a process that finished in time goes on untouched.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "common/log/logging.h"
#include "common/node/shutdown_signal.h"

namespace rslam {
namespace {

using std::chrono::milliseconds;

class ExitDeadlineTest : public testing::Test {
 protected:
  void SetUp() override { GTEST_FLAG_SET(death_test_style, "threadsafe"); }
};

// A teardown that never finishes: without the deadline the process would exit 9 after 10 s.
[[noreturn]] void Hang() {
  std::this_thread::sleep_for(std::chrono::seconds(10));
  std::_Exit(9);
}

TEST_F(ExitDeadlineTest, EndsAProcessThatHangsPastIt) {
  EXPECT_EXIT(
      {
        SetupLogging("test");
        ExitDeadline deadline(milliseconds(50), "the test's teardown");
        Hang();
      },
      testing::ExitedWithCode(0), "the test's teardown did not finish within 50 ms: exiting without it");
}

TEST_F(ExitDeadlineTest, LeavesAProcessThatFinishedInTime) {
  // The process outlives the deadline's time by 250 ms and then exits with its own code.
  EXPECT_EXIT(
      {
        SetupLogging("test");
        { ExitDeadline deadline(milliseconds(50), "the test's teardown"); }
        std::this_thread::sleep_for(milliseconds(300));
        std::_Exit(7);
      },
      testing::ExitedWithCode(7), "");
}

}  // namespace
}  // namespace rslam
