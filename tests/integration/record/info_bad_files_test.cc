// `rslam info` refuses damaged recordings (truncated, wrong magic, bad CRC, wrong record
// lengths) with a clear error naming the file and exit code 1, and describes a good one.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/integration/record/record_test_util.h"
#include "tools/record/recorded_topic.h"
#include "tools/record/recording_writer.h"

namespace rslam::record {
namespace {

using namespace testing;

std::vector<char> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteBytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A good recording: 30 velocities and 3 small images of robot1, chunks uncompressed so a flipped
// byte reaches the CRC check rather than the decompressor.
std::string WriteGoodRecording(const fs::path& dir) {
  RecordingFileOptions o;
  o.path = (dir / "good.mcap").string();
  o.compression = "none";
  o.chunk_size = 16 * 1024;
  RecordingWriter w(o, "cyclone");
  for (int i = 0; i < 30; ++i) {
    msg::Velocity v;
    FillExample(v, i);
    w.Write(TopicTable()[1], "robot1", 1000 + i, 1000 + i, bus::ToCdr(v));
    if (i % 10 == 0) w.Write(TopicTable()[0], "robot1", 1000 + i, 1000 + i, bus::ToCdr(MakeImage("robot1", i, 64, 48)));
  }
  w.Close();
  return o.path;
}

void ExpectRefused(const std::string& path, const fs::path& log, const std::string& why) {
  const CliResult r = RunCli({"info", path}, log);
  EXPECT_EQ(r.code, 1) << why << ":\n" << r.output;
  EXPECT_NE(r.output.find(path), std::string::npos) << why << ": the error must name the file:\n" << r.output;
  const CliResult j = RunCli({"info", path, "--json"}, log);
  EXPECT_EQ(j.code, 1) << why << " (--json):\n" << j.output;
}

TEST(InfoBadFiles, GoodRecordingIsDescribed) {
  const auto dir = ScratchFolderForTest();
  const std::string good = WriteGoodRecording(dir);
  const CliResult r = RunCli({"info", good, "--json"}, dir / "info.log");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["message_count"], 33);
  EXPECT_EQ(j["compression"], nlohmann::json::array({"none"}));
  EXPECT_EQ(j["robots"], nlohmann::json::array({"robot1"}));
  const CliResult text = RunCli({"info", good}, dir / "text.log");
  ASSERT_EQ(text.code, 0) << text.output;
  EXPECT_NE(text.output.find("/robot1/odometry/velocity"), std::string::npos) << text.output;
}

TEST(InfoBadFiles, TruncatedFileIsRefused) {
  const auto dir = ScratchFolderForTest();
  const auto bytes = ReadBytes(WriteGoodRecording(dir));
  for (std::size_t keep : {bytes.size() - 1, bytes.size() / 2, std::size_t{20}, std::size_t{0}}) {
    const std::string path = (dir / ("cut_" + std::to_string(keep) + ".mcap")).string();
    WriteBytes(path, std::vector<char>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(keep)));
    ExpectRefused(path, dir / "info.log", "truncated to " + std::to_string(keep) + " bytes");
  }
}

TEST(InfoBadFiles, WrongMagicIsRefused) {
  const auto dir = ScratchFolderForTest();
  auto bytes = ReadBytes(WriteGoodRecording(dir));
  auto head = bytes;
  head[1] = 'X';
  WriteBytes((dir / "head.mcap").string(), head);
  ExpectRefused((dir / "head.mcap").string(), dir / "info.log", "bad leading magic");
  auto tail = bytes;
  tail[tail.size() - 2] = 'X';
  WriteBytes((dir / "tail.mcap").string(), tail);
  ExpectRefused((dir / "tail.mcap").string(), dir / "info.log", "bad closing magic");
}

TEST(InfoBadFiles, FlippedPayloadByteFailsTheCrc) {
  const auto dir = ScratchFolderForTest();
  auto bytes = ReadBytes(WriteGoodRecording(dir));
  // Inside the first chunk's records (after magic 8 + header record and the chunk's fields).
  bytes[400] = static_cast<char>(bytes[400] ^ 0x5A);
  WriteBytes((dir / "crc.mcap").string(), bytes);
  ExpectRefused((dir / "crc.mcap").string(), dir / "info.log", "flipped byte");
}

TEST(InfoBadFiles, WrongRecordLengthIsRefused) {
  const auto dir = ScratchFolderForTest();
  auto bytes = ReadBytes(WriteGoodRecording(dir));
  // The Header record's length field (right after the magic and its opcode): too long, too short.
  for (uint64_t length : {uint64_t{1} << 40, uint64_t{3}}) {
    auto damaged = bytes;
    std::memcpy(damaged.data() + 9, &length, 8);
    const std::string path = (dir / ("len_" + std::to_string(length) + ".mcap")).string();
    WriteBytes(path, damaged);
    ExpectRefused(path, dir / "info.log", "header length " + std::to_string(length));
  }
}

TEST(InfoBadFiles, MissingFileIsAnError) {
  const auto dir = ScratchFolderForTest();
  const CliResult r = RunCli({"info", (dir / "absent.mcap").string()}, dir / "info.log");
  EXPECT_NE(r.code, 0);
}

}  // namespace
}  // namespace rslam::record
