// State files are written atomically and refused whole when corrupt.

#include <gtest/gtest.h>
#include <google/protobuf/wrappers.pb.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/math/pose2d_proto.h"
#include "common/persistence/state_file.h"

namespace rslam {
namespace {

class StateFileTest : public ::testing::Test {
 protected:
  std::string path_ = (std::filesystem::temp_directory_path() /
                       ("rslam_state_" + std::to_string(::getpid()) + ".pb")).string();
  void TearDown() override { std::filesystem::remove(path_); }
  void FlipByte(std::size_t from_end) {
    std::fstream f(path_, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(-static_cast<long>(from_end), std::ios::end);
    char c;
    f.get(c);
    f.seekp(-static_cast<long>(from_end), std::ios::end);
    f.put(static_cast<char>(c ^ 0x5A));
  }
};

TEST_F(StateFileTest, RoundTrips) {
  google::protobuf::StringValue in;
  in.set_value("experience map");
  WriteStateFile(path_, "test.kind", 1, in);
  google::protobuf::StringValue out;
  EXPECT_EQ(ReadStateFile(path_, "test.kind", 1, out), 1u);
  EXPECT_EQ(out.value(), "experience map");
}

TEST_F(StateFileTest, CorruptForeignOrNewerFilesAreRefused) {
  google::protobuf::StringValue in;
  in.set_value("0123456789");
  WriteStateFile(path_, "test.kind", 2, in);
  google::protobuf::StringValue out;
  EXPECT_THROW(ReadStateFile(path_, "other.kind", 2, out), StateFileError);
  EXPECT_THROW(ReadStateFile(path_, "test.kind", 1, out), StateFileError);
  FlipByte(3);
  EXPECT_THROW(ReadStateFile(path_, "test.kind", 2, out), StateFileError);
  std::filesystem::resize_file(path_, 20);
  EXPECT_THROW(ReadStateFile(path_, "test.kind", 2, out), StateFileError);
  EXPECT_THROW(ReadStateFile(path_ + ".missing", "test.kind", 2, out), StateFileError);
}

// A pose in every service's state file is fields 1, 2, 3 as doubles (x, y, theta), as the
// explorer's, occupancy mapper's and pose cells' own messages were before they shared
// rslam.proto.Pose2D: files saved then must still read the same.
TEST(SavedPoseTest, KeepsTheWireFormatOfTheOlderStateFiles) {
  std::string older;
  for (const auto& [tag, v] : {std::pair{'\x09', 1.5}, {'\x11', -2.0}, {'\x19', 0.25}}) {
    char le[8];
    std::memcpy(le, &v, 8);  // fixed64, little-endian on every platform we build for
    older.push_back(tag);
    older.append(le, 8);
  }
  proto::Pose2D saved;
  SavePose({1.5, -2.0, 0.25}, &saved);
  EXPECT_EQ(saved.SerializeAsString(), older);
  proto::Pose2D read;
  ASSERT_TRUE(read.ParseFromString(older));
  const Pose2D pose = LoadPose(read);
  EXPECT_EQ(pose.x, 1.5);
  EXPECT_EQ(pose.y, -2.0);
  EXPECT_EQ(pose.theta, 0.25);
}

TEST(Crc32Test, MatchesTheStandardCheckValue) {
  EXPECT_EQ(Crc32("123456789", 9), 0xCBF43926u);
}

}  // namespace
}  // namespace rslam
