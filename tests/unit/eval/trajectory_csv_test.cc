#include "tools/eval/trajectory_csv.h"

#include <gtest/gtest.h>

#include <sstream>
#include <stdexcept>
#include <string>

namespace rslam::eval {
namespace {

std::vector<StampedPose2D> Parse(const std::string& text) {
  std::istringstream in(text);
  return ReadTrajectoryCsv(in, "t.csv");
}

std::string ErrorOf(const std::string& text) {
  try {
    Parse(text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(TrajectoryCsv, ReadsPosesWithAndWithoutHeading) {
  const auto with_theta = Parse("# a comment\nstamp_ns,x,y,theta\n100,1.5,-2,0.25\n\n200, 3 ,4e-1,-1\n");
  ASSERT_EQ(with_theta.size(), 2u);
  EXPECT_EQ(with_theta[1].stamp_ns, 200);
  EXPECT_DOUBLE_EQ(with_theta[1].x, 3.0);
  EXPECT_DOUBLE_EQ(with_theta[1].y, 0.4);
  EXPECT_DOUBLE_EQ(*with_theta[0].theta, 0.25);
  const auto reordered = Parse("x,y,stamp_ns\n1,2,3\n");
  EXPECT_EQ(reordered[0].stamp_ns, 3);
  EXPECT_FALSE(reordered[0].theta.has_value());
}

TEST(TrajectoryCsv, BadInputNamesTheLine) {
  EXPECT_EQ(ErrorOf("stamp_ns,x\n1,2\n"), "t.csv:1: header lacks column 'y' (expected stamp_ns,x,y[,theta])");
  EXPECT_EQ(ErrorOf("stamp_ns,x,y,z\n"), "t.csv:1: unknown column 'z' in header (expected stamp_ns,x,y[,theta])");
  EXPECT_EQ(ErrorOf("stamp_ns,x,y\n1,2,3\n2,3\n"), "t.csv:3: expected 3 fields, got 2");
  EXPECT_EQ(ErrorOf("stamp_ns,x,y\n1,2,3\n2,abc,3\n"), "t.csv:3: x 'abc' is not a finite number");
  EXPECT_EQ(ErrorOf("stamp_ns,x,y\n1.5,2,3\n"), "t.csv:2: stamp_ns '1.5' is not an integer number of nanoseconds");
  EXPECT_EQ(ErrorOf("stamp_ns,x,y\n1,nan,3\n"), "t.csv:2: x 'nan' is not a finite number");
  EXPECT_EQ(ErrorOf("stamp_ns,x,y\n"), "t.csv:1: no poses after the header");
  EXPECT_EQ(ErrorOf(""), "t.csv:0: no header line (expected stamp_ns,x,y[,theta])");
}

TEST(TrajectoryCsv, MissingFileIsAClearError) {
  EXPECT_THROW(ReadTrajectoryCsvFile("/nonexistent/trajectory.csv"), std::runtime_error);
}

}  // namespace
}  // namespace rslam::eval
