#include <gtest/gtest.h>

#include "common/mcap/mcap_split_writer.h"
#include "tests/unit/mcap/mcap_test_util.h"

namespace rslam::mcap {
namespace {

using testing::DeclareChannels;
using testing::InLogTimeOrder;
using testing::MakeMessages;
using testing::ReadAll;
using testing::ScratchFolderForTest;
using testing::WriteAll;
using testing::WrittenMessage;

void ExpectSameMessages(const std::vector<WrittenMessage>& expected,
                        const std::vector<WrittenMessage>& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE("message " + std::to_string(i));
    EXPECT_EQ(expected[i].channel, actual[i].channel);
    EXPECT_EQ(expected[i].sequence, actual[i].sequence);
    EXPECT_EQ(expected[i].log_time, actual[i].log_time);
    EXPECT_EQ(expected[i].publish_time, actual[i].publish_time);
    EXPECT_TRUE(expected[i].data == actual[i].data);
  }
}

class McapRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(McapRoundTrip, EveryMessageReadsBackByteEqualInLogTimeOrder) {
  const auto path = ScratchFolderForTest() / "rt.mcap";
  const auto msgs = MakeMessages(600);
  McapWriterOptions options;
  options.compression = GetParam();
  options.chunk_size = 32 * 1024;  // many chunks
  options.profile = "rslam";
  {
    McapWriter w;
    w.Open(path, options);
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Close();
  }
  const McapReader r(path.string());
  EXPECT_EQ(r.profile(), "rslam");
  EXPECT_EQ(r.library(), kRslamMcapLibrary);
  EXPECT_TRUE(r.has_summary());
  ASSERT_EQ(r.schemas().size(), 2u);
  EXPECT_EQ(r.schemas().at(1).name, "rslam::msg::Ping");
  EXPECT_EQ(r.schemas().at(1).encoding, "omgidl");
  EXPECT_EQ(r.schemas().at(1).data, testing::kPingIdl);
  ASSERT_EQ(r.channels().size(), 3u);
  const Channel& cam = r.channels().at(2);
  EXPECT_EQ(cam.topic, "/robot1/camera/image");
  EXPECT_EQ(cam.schema_id, 2);
  EXPECT_EQ(cam.message_encoding, "cdr");
  EXPECT_EQ(cam.metadata.at("qos"), "sensor");
  EXPECT_EQ(cam.metadata.at("dds_topic"), "rt/robot1/camera/image");
  EXPECT_EQ(r.channels().at(3).metadata.at("dds_vendor"), "fastdds");

  const Statistics& s = r.statistics();
  EXPECT_EQ(s.message_count, msgs.size());
  EXPECT_EQ(s.channel_message_counts.at(1), 200u);
  EXPECT_EQ(s.channel_message_counts.at(2), 200u);
  EXPECT_EQ(s.message_start_time, 1'000'000'000ull + 1'000'000ull - 2'500'000ull);
  EXPECT_EQ(s.message_end_time, 1'000'000'000ull + 599ull * 1'000'000ull);
  EXPECT_GT(r.chunks().size(), 10u);
  EXPECT_EQ(s.chunk_count, r.chunks().size());
  for (const auto& c : r.chunks()) EXPECT_EQ(c.compression, GetParam());
  if (!GetParam().empty()) {
    uint64_t compressed = 0, plain = 0;
    for (const auto& c : r.chunks()) {
      compressed += c.compressed_size;
      plain += c.uncompressed_size;
    }
    EXPECT_LT(compressed, plain);
  }
  ExpectSameMessages(InLogTimeOrder(msgs), ReadAll(r));
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapRoundTrip, ::testing::Values("zstd", "lz4", ""),
                         [](const auto& info) {
                           return info.param.empty() ? std::string("none") : info.param;
                         });

TEST(McapReader, FiltersByTopicAndInclusiveTimeRange) {
  const auto path = ScratchFolderForTest() / "f.mcap";
  const auto msgs = MakeMessages(300);
  {
    McapWriter w;
    McapWriterOptions o;
    o.chunk_size = 16 * 1024;
    w.Open(path, o);
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Close();
  }
  const McapReader r(path.string());
  MessageFilter f;
  f.topics = {"/robot1/ping", "/robot2/ping"};
  f.start_time = msgs[30].log_time;
  f.end_time = msgs[90].log_time;
  std::vector<WrittenMessage> expected;
  for (const auto& m : InLogTimeOrder(msgs)) {
    if (m.channel != 2 && m.log_time >= f.start_time && m.log_time <= f.end_time) {
      expected.push_back(m);
    }
  }
  ASSERT_FALSE(expected.empty());
  ExpectSameMessages(expected, ReadAll(r, f));
}

TEST(McapWriter, FileWithoutMessagesIsValid) {
  const auto path = ScratchFolderForTest() / "empty.mcap";
  {
    McapWriter w;
    w.Open(path);
    DeclareChannels(w);
    w.Close();
  }
  const McapReader r(path.string());
  EXPECT_EQ(r.statistics().message_count, 0u);
  EXPECT_EQ(r.channels().size(), 3u);
  EXPECT_TRUE(ReadAll(r).empty());
}

TEST(McapWriter, RejectsUnknownChannelAndBadOptions) {
  const auto dir = ScratchFolderForTest();
  McapWriter w;
  McapWriterOptions bad;
  bad.compression = "brotli";
  EXPECT_THROW(w.Open(dir / "bad.mcap", bad), std::invalid_argument);
  w.Open(dir / "ok.mcap");
  DeclareChannels(w);
  const std::vector<std::byte> d(4);
  EXPECT_THROW(w.Write(0, 0, 0, 0, d), std::invalid_argument);
  EXPECT_THROW(w.Write(9, 0, 0, 0, d), std::invalid_argument);
  EXPECT_THROW(w.AddChannel(7, "/x", "cdr", {}), std::invalid_argument);
  w.Close();
}

TEST(McapSplitWriter, SplitsBySizeAndEveryFileReadsBackCompletely) {
  const auto dir = ScratchFolderForTest();
  const auto msgs = MakeMessages(900);
  McapWriterOptions o;
  o.chunk_size = 16 * 1024;
  McapSplitOptions split;
  split.max_file_bytes = 200 * 1024;
  std::vector<std::string> paths;
  {
    McapSplitWriter w((dir / "rec.mcap").string(), o, split);
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Close();
    paths = w.paths();
  }
  ASSERT_GE(paths.size(), 3u);
  EXPECT_EQ(paths[0], (dir / "rec_0000.mcap").string());
  EXPECT_EQ(paths[1], (dir / "rec_0001.mcap").string());
  std::vector<WrittenMessage> all;
  for (const auto& p : paths) {
    const McapReader r(p);
    EXPECT_EQ(r.channels().size(), 3u) << p;
    EXPECT_EQ(r.schemas().size(), 2u) << p;
    EXPECT_EQ(r.channels().at(2).metadata.at("qos"), "sensor") << p;
    EXPECT_GT(r.statistics().message_count, 0u) << p;
    auto part = ReadAll(r);
    all.insert(all.end(), part.begin(), part.end());
  }
  ASSERT_EQ(all.size(), msgs.size());
  std::sort(all.begin(), all.end(), [](auto& a, auto& b) { return a.sequence < b.sequence; });
  for (std::size_t i = 0; i < msgs.size(); ++i) {
    EXPECT_EQ(all[i].sequence, msgs[i].sequence);
    EXPECT_TRUE(all[i].data == msgs[i].data);
  }
}

TEST(McapSplitWriter, SplitsByLogTimeDuration) {
  const auto dir = ScratchFolderForTest();
  const auto msgs = MakeMessages(300);  // ~300 ms of log time
  McapSplitOptions split;
  split.max_file_duration_ns = 100'000'000;
  std::vector<std::string> paths;
  {
    McapSplitWriter w((dir / "rec").string(), {}, split);
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Close();
    paths = w.paths();
  }
  ASSERT_GE(paths.size(), 3u);
  ASSERT_LE(paths.size(), 4u);
  uint64_t total = 0;
  for (const auto& p : paths) {
    const McapReader r(p);
    total += r.statistics().message_count;
    EXPECT_LE(r.statistics().message_end_time - r.statistics().message_start_time,
              100'000'000ull + 2'500'000ull);
  }
  EXPECT_EQ(total, msgs.size());
}

}  // namespace
}  // namespace rslam::mcap
