// A recorder killed with SIGKILL mid-stream leaves a file that `rslam info` refuses (pointing at
// --recover) and that `rslam info FILE --recover OUT` turns into a valid recording holding every
// message of every complete chunk.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "common/bus/topics.h"
#include "common/mcap/chunk_compression.h"
#include "tests/integration/record/record_test_util.h"
#include "tests/support/test_domain.h"

namespace rslam::record {
namespace {

using namespace testing;

// Messages in the complete Chunk records of an unfinished file, counted independently of the
// recovery code: walk the records after the header, decompress each whole chunk, count its
// Message records; stop at the first record that runs past the end of the file.
uint64_t MessagesInCompleteChunks(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> file(chars.size());
  std::memcpy(file.data(), chars.data(), chars.size());
  uint64_t messages = 0;
  std::size_t pos = mcap::kMagic.size();
  std::vector<std::byte> records;
  while (pos + mcap::kRecordPrefixSize <= file.size()) {
    const auto opcode = static_cast<mcap::Opcode>(file[pos]);
    uint64_t length;
    std::memcpy(&length, file.data() + pos + 1, 8);
    if (length > file.size() - pos - mcap::kRecordPrefixSize) break;  // the cut-off record
    const std::span<const std::byte> content(file.data() + pos + mcap::kRecordPrefixSize, length);
    if (opcode == mcap::Opcode::kChunk) {
      mcap::RecordCursor c(content, pos + mcap::kRecordPrefixSize, "chunk");
      c.U64();  // message start time
      c.U64();  // message end time
      const uint64_t uncompressed_size = c.U64();
      c.U32();  // uncompressed crc
      const std::string compression = c.String();
      const uint64_t compressed_size = c.U64();
      mcap::DecompressChunk(compression, c.Bytes(compressed_size), uncompressed_size, pos, records);
      for (std::size_t r = 0; r + mcap::kRecordPrefixSize <= records.size();) {
        uint64_t n;
        std::memcpy(&n, records.data() + r + 1, 8);
        if (static_cast<mcap::Opcode>(records[r]) == mcap::Opcode::kMessage) ++messages;
        r += mcap::kRecordPrefixSize + n;
      }
    }
    pos += mcap::kRecordPrefixSize + length;
  }
  return messages;
}

TEST(KilledRecorder, RecoverKeepsEveryMessageOfTheCompleteChunks) {
  rslam::testing::TestDomain domain;
  const auto dir = ScratchFolderForTest();
  const std::string file = (dir / "killed.mcap").string();
  const std::string repaired = (dir / "repaired.mcap").string();
  ChildProcess recorder(Cli(), {"record", "-o", file, "--domain", std::to_string(domain.id()), "--topics",
                         "^(camera/image|odometry/velocity)$"},
                        {.environment = {}, .log_file = (dir / "record.log").string()});
  auto robot = MakeParticipant(domain.id(), "robot1");
  auto images = robot->CreateRawWriter(bus::TopicSpec{"camera/image", "rslam::msg::Image",
                                                      bus::KeyReaderFor<msg::Image>(), bus::QosPreset::kSensor, "robot1"});
  auto velocities = robot->CreateRawWriter(bus::TopicSpec{"odometry/velocity", "rslam::msg::Velocity",
                                                          bus::KeyReaderFor<msg::Velocity>(), bus::QosPreset::kStream,
                                                          "robot1"});
  ASSERT_TRUE(WaitForReaders(std::vector<bus::RawWriter*>{images.get(), velocities.get()}, 1, 15s));
  ASSERT_TRUE(recorder.WaitForOutput("camera/image (robot *): 1 publisher(s)", 15s)) << recorder.Output();
  ASSERT_TRUE(recorder.WaitForOutput("odometry/velocity (robot *): 1 publisher(s)", 15s)) << recorder.Output();

  // Publish until the file holds several chunks (4 MiB each, about 4 images), then kill the
  // recorder while messages are still flowing.
  std::map<uint64_t, std::vector<uint8_t>> sent_images;
  std::map<uint64_t, std::vector<uint8_t>> sent_velocities;
  uint64_t seq = 0;
  bool killed = false;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (std::chrono::steady_clock::now() < deadline) {
    auto image = bus::ToCdr(MakeImage("robot1", seq));
    images->Write(image);
    sent_images[seq] = Padded(image);
    ASSERT_TRUE(images->WaitForAcknowledgments(10s));
    msg::Velocity v;
    FillExample(v, static_cast<int>(seq));
    v.header = {"robot1", seq, static_cast<int64_t>(seq)};
    auto cdr = bus::ToCdr(v);
    velocities->Write(cdr);
    sent_velocities[seq] = Padded(cdr);
    ++seq;
    std::error_code ec;
    if (fs::file_size(file, ec) > 10u << 20) {
      // Killed right after a write, with that message still in flight. No more writes: the dead
      // reader stays matched until its lease expires, so acknowledgments would time out.
      recorder.Signal(SIGKILL);
      killed = true;
      break;
    }
  }
  ASSERT_TRUE(killed) << "the recording never grew past 10 MiB";
  ASSERT_EQ(recorder.WaitExit(10s), 128 + SIGKILL);

  // info refuses the unfinished file and says how to repair it.
  const CliResult refused = RunCli({"info", file}, dir / "info_refused.log");
  EXPECT_EQ(refused.code, 1) << refused.output;
  EXPECT_NE(refused.output.find("--recover"), std::string::npos) << refused.output;

  const CliResult recovered = RunCli({"info", file, "--recover", repaired, "--json"}, dir / "info_recover.log");
  ASSERT_EQ(recovered.code, 0) << recovered.output;
  const auto j = nlohmann::json::parse(recovered.output);
  const uint64_t expected = MessagesInCompleteChunks(file);
  EXPECT_GT(expected, 4u);
  EXPECT_EQ(j["recovered"]["messages"], expected);
  EXPECT_EQ(j["message_count"], expected);

  // The repaired file is valid and everything in it is what was published, in order, gap-free.
  const auto channels = ReadChannels({repaired});
  uint64_t total = 0;
  for (const auto& [key, list] : channels) {
    const auto& sent = key.first == "camera/image" ? sent_images : sent_velocities;
    for (std::size_t i = 0; i < list.size(); ++i) {
      ASSERT_TRUE(sent.count(i));
      EXPECT_EQ(list[i], sent.at(i)) << key.first << " message " << i;
    }
    total += list.size();
  }
  EXPECT_EQ(total, expected);
  EXPECT_LE(total, 2 * seq);

  // And info accepts it.
  const CliResult info = RunCli({"info", repaired}, dir / "info.log");
  EXPECT_EQ(info.code, 0) << info.output;
}

}  // namespace
}  // namespace rslam::record
