// The Recorder library on the bus: every compression mode and both kinds of file splitting read
// back completely and byte-identical, with nothing dropped.
#include <gtest/gtest.h>

#include "common/bus/topics.h"
#include "tests/integration/record/record_test_util.h"
#include "tests/support/test_domain.h"
#include "tools/record/recorder.h"

namespace rslam::record {
namespace {

using namespace testing;

// robot1 publishing images and velocities to an in-process recorder on a private domain.
class RecordFiles : public ::testing::Test {
 protected:
  void StartRecorder(RecorderOptions options, bus::Vendor recorder_vendor = bus::Vendor::kCyclone) {
    options.topics_regex = "^(camera/image|odometry/velocity)$";
    recorder_participant_ = MakeParticipant(domain_.id(), "rslam-record", recorder_vendor);
    recorder_ = std::make_unique<Recorder>(*recorder_participant_, options);
    robot_ = MakeParticipant(domain_.id(), "robot1");
    images_ = robot_->CreateRawWriter(bus::TopicSpec{"camera/image", "rslam::msg::Image",
                                                     bus::KeyReaderFor<msg::Image>(), bus::QosPreset::kSensor, "robot1"});
    velocities_ = robot_->CreateRawWriter(bus::TopicSpec{"odometry/velocity", "rslam::msg::Velocity",
                                                         bus::KeyReaderFor<msg::Velocity>(), bus::QosPreset::kStream,
                                                         "robot1"});
    ASSERT_TRUE(WaitForReaders(std::vector<bus::RawWriter*>{images_.get(), velocities_.get()}, 1, 15s));
    const auto deadline = std::chrono::steady_clock::now() + 15s;
    while (true) {
      bool all = true;
      for (const auto& s : recorder_->Subscriptions()) all = all && s.matched_writers >= 1;
      if (all) break;
      ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "recorder readers did not match";
      std::this_thread::sleep_for(10ms);  // DDS offers no wait on matching
    }
  }
  void SendImage(uint64_t seq, uint32_t width = 640, uint32_t height = 480) {
    auto cdr = bus::ToCdr(MakeImage("robot1", seq, width, height));
    images_->Write(cdr);
    sent_[{"camera/image", "robot1"}].push_back(Padded(cdr));
    ASSERT_TRUE(images_->WaitForAcknowledgments(10s));
  }
  void SendVelocity(uint64_t seq) {
    msg::Velocity v;
    FillExample(v, static_cast<int>(seq));
    v.header = {"robot1", seq, static_cast<int64_t>(seq)};
    auto cdr = bus::ToCdr(v);
    velocities_->Write(cdr);
    sent_[{"odometry/velocity", "robot1"}].push_back(Padded(cdr));
  }
  // Stops the recorder and checks that the files hold exactly what was sent.
  std::vector<std::string> StopAndCheck() {
    EXPECT_TRUE(images_->WaitForAcknowledgments(10s));
    EXPECT_TRUE(velocities_->WaitForAcknowledgments(10s));
    recorder_->Stop();
    const RecorderStats st = recorder_->Stats();
    EXPECT_EQ(st.dropped, 0u);
    EXPECT_EQ(st.unattributed, 0u);
    const auto paths = recorder_->paths();
    EXPECT_EQ(ReadChannels(paths), sent_);
    uint64_t total = 0;
    for (const auto& [k, v] : sent_) total += v.size();
    EXPECT_EQ(st.written, total);
    return paths;
  }

  rslam::testing::TestDomain domain_;
  std::unique_ptr<bus::Participant> recorder_participant_;
  std::unique_ptr<Recorder> recorder_;
  std::unique_ptr<bus::Participant> robot_;
  std::unique_ptr<bus::RawWriter> images_;
  std::unique_ptr<bus::RawWriter> velocities_;
  std::map<ChannelKey, std::vector<std::vector<uint8_t>>> sent_;
};

class RecordCompression : public RecordFiles, public ::testing::WithParamInterface<std::string> {};

TEST_P(RecordCompression, EveryMessageReadsBackInEachCompressionMode) {
  const auto dir = ScratchFolderForTest();
  RecorderOptions o;
  o.file.path = (dir / "c.mcap").string();
  o.file.compression = GetParam();
  o.file.chunk_size = 256 * 1024;
  StartRecorder(o);
  for (uint64_t i = 0; i < 60; ++i) {
    if (i % 5 == 0) SendImage(i, 320, 240);
    SendVelocity(i);
  }
  const auto paths = StopAndCheck();
  ASSERT_EQ(paths.size(), 1u);
  const mcap::McapReader reader(paths[0]);
  EXPECT_EQ(reader.profile(), "rslam");
  EXPECT_GT(reader.chunks().size(), 1u);
  for (const auto& c : reader.chunks()) EXPECT_EQ(c.compression, GetParam() == "none" ? "" : GetParam());
}

INSTANTIATE_TEST_SUITE_P(Modes, RecordCompression, ::testing::Values("zstd", "lz4", "none"),
                         [](const auto& info) { return info.param; });

TEST_F(RecordFiles, SplitBySizeKeepsEveryMessageAcrossFiles) {
  const auto dir = ScratchFolderForTest();
  RecorderOptions o;
  o.file.path = (dir / "split.mcap").string();
  o.file.split_bytes = 2'000'000;
  o.file.chunk_size = 1 << 20;
  StartRecorder(o);
  for (uint64_t i = 0; i < 12; ++i) {
    SendImage(i);
    SendVelocity(i);
  }
  const auto paths = StopAndCheck();
  EXPECT_GE(paths.size(), 3u);
  for (std::size_t i = 0; i < paths.size(); ++i) {
    EXPECT_EQ(fs::path(paths[i]).filename().string(), "split_000" + std::to_string(i) + ".mcap");
    const mcap::McapReader reader(paths[i]);  // each file valid on its own
    EXPECT_GT(reader.statistics().message_count, 0u) << paths[i];
  }
}

TEST_F(RecordFiles, SplitByDurationKeepsEveryMessageAcrossFiles) {
  const auto dir = ScratchFolderForTest();
  RecorderOptions o;
  o.file.path = (dir / "timed.mcap").string();
  o.file.split_duration_ns = 200'000'000;
  StartRecorder(o);
  uint64_t seq = 0;
  for (int burst = 0; burst < 4; ++burst) {
    if (burst > 0) std::this_thread::sleep_for(300ms);  // the split is by log (receive) time: let time pass
    for (int i = 0; i < 10; ++i) SendVelocity(seq++);
  }
  const auto paths = StopAndCheck();
  EXPECT_GE(paths.size(), 2u);
  for (const auto& p : paths) {
    const mcap::McapReader reader(p);
    const auto& st = reader.statistics();
    EXPECT_LT(st.message_end_time - st.message_start_time, 200'000'000u) << p;
  }
}

TEST_F(RecordFiles, FastDdsRecorderRecordsCyclonePublishers) {
  const auto dir = ScratchFolderForTest();
  RecorderOptions o;
  o.file.path = (dir / "interop.mcap").string();
  StartRecorder(o, bus::Vendor::kFastDds);
  for (uint64_t i = 0; i < 20; ++i) {
    if (i % 4 == 0) SendImage(i);
    SendVelocity(i);
  }
  const auto paths = StopAndCheck();
  const mcap::McapReader reader(paths.at(0));
  for (const auto& [id, c] : reader.channels()) EXPECT_EQ(c.metadata.at(mcap::kMetadataDdsVendor), "fastdds");
}

TEST(RecordRobots, RobotOptionRecordsOnlyThoseRobotsPartitions) {
  rslam::testing::TestDomain domain;
  const auto dir = ScratchFolderForTest();
  RecorderOptions o;
  o.file.path = (dir / "robot2.mcap").string();
  o.topics_regex = "^odometry/velocity$";
  o.robots = {"robot2"};
  auto recorder_participant = MakeParticipant(domain.id(), "rslam-record");
  Recorder recorder(*recorder_participant, o);
  ASSERT_EQ(recorder.Subscriptions().size(), 1u);
  EXPECT_EQ(recorder.Subscriptions()[0].partition, "robot2");
  std::vector<std::unique_ptr<bus::Participant>> robots;
  std::vector<std::unique_ptr<bus::RawWriter>> writers;
  for (const std::string robot : {"robot1", "robot2"}) {
    robots.push_back(MakeParticipant(domain.id(), robot));
    writers.push_back(robots.back()->CreateRawWriter(bus::TopicSpec{
        "odometry/velocity", "rslam::msg::Velocity", bus::KeyReaderFor<msg::Velocity>(), bus::QosPreset::kStream, robot}));
  }
  ASSERT_TRUE(WaitForReaders(std::vector<bus::RawWriter*>{writers[1].get()}, 1, 15s));
  const auto deadline = std::chrono::steady_clock::now() + 15s;
  while (recorder.Subscriptions()[0].matched_writers < 1) {
    ASSERT_LT(std::chrono::steady_clock::now(), deadline);
    std::this_thread::sleep_for(10ms);  // DDS offers no wait on matching
  }
  std::vector<std::vector<uint8_t>> robot2_sent;
  for (int i = 0; i < 10; ++i) {
    for (std::size_t r = 0; r < 2; ++r) {
      msg::Velocity v;
      FillExample(v, i);
      v.header.robot_id = r == 0 ? "robot1" : "robot2";
      auto cdr = bus::ToCdr(v);
      writers[r]->Write(cdr);
      if (r == 1) robot2_sent.push_back(Padded(cdr));
    }
  }
  ASSERT_TRUE(writers[1]->WaitForAcknowledgments(10s));
  recorder.Stop();
  const auto channels = ReadChannels(recorder.paths());
  ASSERT_EQ(channels.size(), 1u) << "only robot2's channel";
  EXPECT_EQ(channels.at({"odometry/velocity", "robot2"}), robot2_sent);
}

}  // namespace
}  // namespace rslam::record
