// Pins LocalViewActivation to paper 001 eq. 2.
#include "services/templates/local_view_activation.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace rslam::templates {
namespace {

TEST(LocalViewActivationTest, IsEq2NormalisedToUnity) {
  const std::vector<double> d = {0.1, 0.3, 0.05, 0.5};
  const std::vector<double> v = LocalViewActivation(d, 0.35, 0.01);
  const double a = 1 / 0.11, b = 1 / 0.31, c = 1 / 0.06, total = a + b + c;
  ASSERT_EQ(v.size(), 4u);
  EXPECT_DOUBLE_EQ(v[0], a / total);
  EXPECT_DOUBLE_EQ(v[1], b / total);
  EXPECT_DOUBLE_EQ(v[2], c / total);
  EXPECT_EQ(v[3], 0.0);  // d > d_max
  // d == d_max is still active.
  EXPECT_GT(LocalViewActivation(std::vector<double>{0.35}, 0.35, 0.01)[0], 0.0);
}

TEST(LocalViewActivationTest, NothingWithinDmaxGivesAllZeros) {
  const std::vector<double> v = LocalViewActivation(std::vector<double>{1.0, 2.0}, 0.5, 0.01);
  EXPECT_EQ(v, (std::vector<double>{0.0, 0.0}));
  EXPECT_TRUE(LocalViewActivation(std::vector<double>{}, 0.5, 0.01).empty());
}

TEST(LocalViewActivationTest, RejectsBadInput) {
  const std::vector<double> ok = {0.1};
  EXPECT_THROW(LocalViewActivation(ok, 0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(LocalViewActivation(ok, std::numeric_limits<double>::quiet_NaN(), 0.01), std::invalid_argument);
  EXPECT_THROW(LocalViewActivation(std::vector<double>{-0.1}, 0.5, 0.01), std::invalid_argument);
  EXPECT_THROW(LocalViewActivation(std::vector<double>{std::numeric_limits<double>::quiet_NaN()}, 0.5, 0.01),
               std::invalid_argument);
  // An infinite difference (e.g. an empty-library report) is simply inactive.
  EXPECT_EQ(LocalViewActivation(std::vector<double>{std::numeric_limits<double>::infinity()}, 0.5, 0.01)[0], 0.0);
}

}  // namespace
}  // namespace rslam::templates
