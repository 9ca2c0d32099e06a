// What `rslam run` prints as it goes: the bar on a terminal, plain lines otherwise, nothing when quiet.

#include "tools/run/progress_reporter.h"

#include <gtest/gtest.h>

#include <sstream>

namespace rslam::run {
namespace {

TEST(ProgressReporter, BarShowsTheShareDoneAndTheCounts) {
  std::ostringstream out;
  ProgressReporter progress(out, ProgressReporter::Style::kBar, 200);
  progress.Finish(50, 7, 9);
  const std::string text = out.str();
  EXPECT_NE(text.find("[#######.......................] 25%  50/200 frames"), std::string::npos) << text;
  EXPECT_NE(text.find("7 templates  9 experiences"), std::string::npos) << text;
  EXPECT_EQ(text.back(), '\n');
}

TEST(ProgressReporter, LinesWithoutAKnownTotalShowNoBarAndNoTotal) {
  std::ostringstream out;
  ProgressReporter progress(out, ProgressReporter::Style::kLines, -1);
  progress.Finish(120, 3, 4);
  const std::string text = out.str();
  EXPECT_EQ(text.rfind("rslam run: 120 frames  ", 0), 0u) << text;
  EXPECT_EQ(text.find('['), std::string::npos) << text;
  EXPECT_NE(text.find("3 templates  4 experiences\n"), std::string::npos) << text;
}

TEST(ProgressReporter, QuietPrintsNothing) {
  std::ostringstream out;
  ProgressReporter progress(out, ProgressReporter::Style::kQuiet, 10);
  progress.Update(5, 1, 1);
  progress.Finish(10, 1, 1);
  EXPECT_TRUE(out.str().empty());
}

}  // namespace
}  // namespace rslam::run
