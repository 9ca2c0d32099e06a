// UnmatchedLinks: which links among services' heartbeats discovery has not matched at both ends.
#include <gtest/gtest.h>

#include "common/node/heartbeat.h"

namespace rslam {
namespace {

msg::ServiceStatus Service(const std::string& name, std::vector<msg::EndpointMatch> endpoints) {
  msg::ServiceStatus s;
  s.service = name;
  s.endpoints = std::move(endpoints);
  return s;
}

TEST(UnmatchedLinksTest, ALinkCountsOnlyBetweenTheGivenServicesAndNeedsBothEnds) {
  const auto odometry = Service("odometry", {{"camera/image", false, 0}, {"odometry/velocity", true, 0}});
  const auto pose_cells = Service("pose_cells", {{"odometry/velocity", false, 1}, {"pose_cells/action", true, 0}});
  // Nobody among them writes camera/image or reads pose_cells/action: those are not links.
  EXPECT_EQ(UnmatchedLinks({odometry, pose_cells}),
            std::vector<std::string>{"odometry: writer of odometry/velocity matched 0 of 1"});
  auto matched = odometry;
  matched.endpoints[1].matched = 1;
  EXPECT_TRUE(UnmatchedLinks({matched, pose_cells}).empty());
}

TEST(UnmatchedLinksTest, AWriterMustHaveMatchedEveryReadingService) {
  const auto templates = Service("templates", {{"templates/view", true, 1}});
  const auto pose_cells = Service("pose_cells", {{"templates/view", false, 1}});
  const auto occupancy = Service("occupancy", {{"templates/view", false, 1}});
  EXPECT_EQ(UnmatchedLinks({templates, pose_cells, occupancy}),
            std::vector<std::string>{"templates: writer of templates/view matched 1 of 2"});
}

TEST(UnmatchedLinksTest, NoHeartbeatsNoLinks) { EXPECT_TRUE(UnmatchedLinks({}).empty()); }

}  // namespace
}  // namespace rslam
