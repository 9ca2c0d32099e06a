// FrameJoiner: the node's join of camera images and experience-map poses by frame number.
// (A unit test of the node's helper; it lives beside the service's integration test.)

#include "services/occupancy/frame_joiner.h"

#include <gtest/gtest.h>

#include <string>

namespace rslam::occupancy {
namespace {

using Joiner = FrameJoiner<std::string, int>;

TEST(FrameJoinerTest, JoinsByFrameNumberInEitherOrder) {
  Joiner joiner(8);
  EXPECT_FALSE(joiner.AddA(1, "image1"));
  auto first = joiner.AddB(1, 10);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->frame_seq, 1u);
  EXPECT_EQ(first->a, "image1");
  EXPECT_EQ(first->b, 10);

  EXPECT_FALSE(joiner.AddB(2, 20));
  auto second = joiner.AddA(2, "image2");
  ASSERT_TRUE(second);
  EXPECT_EQ(second->a, "image2");
  EXPECT_EQ(second->b, 20);
  EXPECT_EQ(joiner.dropped(), 0u);
  EXPECT_EQ(joiner.waiting(), 0u);
}

TEST(FrameJoinerTest, DropsEntriesThatCanNoLongerBeJoined) {
  Joiner joiner(8);
  EXPECT_FALSE(joiner.AddA(1, "lost pose"));  // its pose never comes
  EXPECT_FALSE(joiner.AddA(2, "image2"));
  ASSERT_TRUE(joiner.AddB(2, 20));
  EXPECT_EQ(joiner.dropped(), 1u);  // frame 1's image is older than the joined frame 2
  EXPECT_FALSE(joiner.AddB(1, 10));  // a pose for frame 1 arriving late
  EXPECT_EQ(joiner.dropped(), 2u);
  EXPECT_EQ(joiner.waiting(), 0u);
}

TEST(FrameJoinerTest, BoundsEachBufferByDroppingTheOldest) {
  Joiner joiner(3);
  for (uint64_t seq = 1; seq <= 5; ++seq) EXPECT_FALSE(joiner.AddA(seq, "image"));
  EXPECT_EQ(joiner.waiting(), 3u);
  EXPECT_EQ(joiner.dropped(), 2u);
  EXPECT_FALSE(joiner.AddB(1, 10));  // its image was dropped; the pose waits
  EXPECT_TRUE(joiner.AddB(5, 50));
}

TEST(FrameJoinerTest, StartsOverWhenTheSourceRestartsItsNumbering) {
  Joiner joiner(4);
  joiner.AddA(1000, "image");
  ASSERT_TRUE(joiner.AddB(1000, 1));
  EXPECT_FALSE(joiner.AddA(0, "new run"));  // far below: a new camera run
  EXPECT_TRUE(joiner.AddB(0, 2));
}

}  // namespace
}  // namespace rslam::occupancy
