// State files are written atomically and refused whole when corrupt.

#include <gtest/gtest.h>
#include <google/protobuf/wrappers.pb.h>

#include <filesystem>
#include <fstream>

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

TEST(Crc32Test, MatchesTheStandardCheckValue) {
  EXPECT_EQ(Crc32("123456789", 9), 0xCBF43926u);
}

}  // namespace
}  // namespace rslam
