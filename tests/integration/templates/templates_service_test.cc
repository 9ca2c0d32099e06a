// rslam-templates as a black box on a private DDS domain: the test plays the camera.

#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/integration/camera/image_test_util.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::ScratchFolder;

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-templates";

class TemplatesServiceTest : public ::testing::Test {
 protected:
  TemplatesServiceTest() {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    images_ = std::make_unique<bus::Publisher<msg::Image>>(*participant_, bus::topics::kCameraImage);
    views_ = std::make_unique<bus::Subscriber<msg::ViewTemplate>>(*participant_, bus::topics::kTemplatesView);
    heartbeats_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
  }

  // Whole-image 32x16 patch templates; a long save period so the journal is what survives a kill.
  std::unique_ptr<ChildProcess> Start(std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"--domain",    std::to_string(domain_.id()), "--state-dir",
                                  state_.path().string(), "--set", "service.heartbeat_period_s=0.2",
                                  "--set",       "service.state_save_period_s=1000"};
    std::vector<std::string> keys{"image_crop_x_min=0", "image_crop_x_max=-1", "image_crop_y_min=0",
                                  "image_crop_y_max=-1", "template_x_size=32",  "template_y_size=16",
                                  "shift_match=4"};
    keys.insert(keys.end(), extra.begin(), extra.end());
    for (const auto& k : keys) {
      args.push_back("--set");
      args.push_back("templates." + k);
    }
    auto process = std::make_unique<ChildProcess>(kBinary, args);
    // Ready when this process's own heartbeat shows its image reader and view writer matched:
    // the test's match counts may still include a process stopped or killed just before.
    const auto pid = static_cast<uint32_t>(process->pid());
    auto ready = [&](const msg::ServiceStatus& s) {
      bool reader = false, writer = false;
      for (const msg::EndpointMatch& e : s.endpoints) {
        if (e.topic == bus::topics::kCameraImage.name && !e.writer) reader = e.matched > 0;
        if (e.topic == bus::topics::kTemplatesView.name && e.writer) writer = e.matched > 0;
      }
      return s.pid == pid && reader && writer;
    };
    const bool matched = testing::WaitFor(
        [&] {
          const auto s = heartbeats_->TakeOne(100ms);
          return s && ready(*s);
        },
        10s);
    EXPECT_TRUE(matched) << process->Output();
    return process;
  }

  static cv::Mat Scene(uint64_t seed) { return testing::SmoothTexture(128, 64, seed); }

  // The view answering frame `seq`. The first frame after a (re)start can be lost while the
  // service's reader is still matching the test's writer, so an unanswered frame is sent again
  // (a repeated image matches the template it made: the answer to the first copy is the one kept).
  std::optional<msg::ViewTemplate> Send(const cv::Mat& image, uint64_t seq) {
    const msg::Image message = testing::ImageMessage(image, seq, static_cast<int64_t>(seq) * 100'000'000);
    for (int attempt = 0; attempt < 5; ++attempt) {
      images_->Publish(message);
      const auto deadline = std::chrono::steady_clock::now() + 1s;
      while (std::chrono::steady_clock::now() < deadline) {
        const auto view = views_->TakeOne(100ms);
        if (view && view->header.frame_seq == seq) return view;
      }
    }
    return std::nullopt;
  }

  testing::TestDomain domain_;
  ScratchFolder state_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::Image>> images_;
  std::unique_ptr<bus::Subscriber<msg::ViewTemplate>> views_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> heartbeats_;
};

TEST_F(TemplatesServiceTest, SameImageMatchesItsTemplateAndADifferentImageIsNew) {
  auto templates = Start();
  const auto first = Send(Scene(1), 0);
  ASSERT_TRUE(first) << templates->Output();
  EXPECT_TRUE(first->is_new);
  EXPECT_EQ(first->template_id, 0u);
  EXPECT_EQ(first->template_count, 1u);
  EXPECT_TRUE(std::isfinite(first->difference)) << "no infinity on the bus";
  EXPECT_EQ(first->header.frame_seq, 0u);
  EXPECT_EQ(first->header.robot_id, "robot1");

  const auto again = Send(Scene(1), 1);
  ASSERT_TRUE(again) << templates->Output();
  EXPECT_FALSE(again->is_new);
  EXPECT_EQ(again->template_id, 0u);
  EXPECT_NEAR(again->difference, 0.0, 1e-9);
  EXPECT_NEAR(again->relative_angle_rad, 0.0, 1e-12);
  EXPECT_EQ(again->header.frame_seq, 1u);

  const auto other = Send(Scene(2), 2);
  ASSERT_TRUE(other) << templates->Output();
  EXPECT_TRUE(other->is_new);
  EXPECT_EQ(other->template_id, 1u);
  EXPECT_EQ(other->template_count, 2u);
}

TEST_F(TemplatesServiceTest, BgrImagesAreMatchedLikeTheirGreyVersion) {
  auto templates = Start();
  cv::Mat bgr;
  cv::cvtColor(Scene(4), bgr, cv::COLOR_GRAY2BGR);
  ASSERT_TRUE(Send(Scene(4), 0)) << templates->Output();
  const auto colour = Send(bgr, 1);
  ASSERT_TRUE(colour) << templates->Output();
  EXPECT_FALSE(colour->is_new);
  EXPECT_EQ(colour->template_id, 0u);
}

TEST_F(TemplatesServiceTest, MalformedImagesAreCountedAndTheServiceKeepsAnswering) {
  auto templates = Start();
  msg::Image bad_step = testing::ImageMessage(Scene(1), 0, 0);
  bad_step.step = 3;
  msg::Image unknown = testing::ImageMessage(Scene(1), 1, 1);
  unknown.encoding = "rgba16";
  msg::Image huge = testing::ImageMessage(Scene(1), 2, 2);
  huge.width = 100000;
  huge.height = 100000;
  for (const auto* bad : {&bad_step, &unknown, &huge}) images_->Publish(*bad);
  const auto good = Send(Scene(1), 3);
  ASSERT_TRUE(good) << templates->Output();
  EXPECT_EQ(good->header.frame_seq, 3u);
  EXPECT_EQ(good->template_id, 0u) << "nothing was learnt from the malformed frames";
  EXPECT_TRUE(testing::AwaitHeartbeat(*heartbeats_, "templates",
                                      [](const msg::ServiceStatus& s) { return s.messages_rejected >= 3; }, 5s))
      << templates->Output();
}

TEST_F(TemplatesServiceTest, RestartAfterSigkillKeepsEveryPublishedTemplate) {
  constexpr int kTemplates = 6;
  {
    auto templates = Start();
    for (int i = 0; i < kTemplates; ++i) {
      const auto view = Send(Scene(100 + i), i);
      ASSERT_TRUE(view) << templates->Output();
      ASSERT_TRUE(view->is_new);
      ASSERT_EQ(view->template_id, static_cast<uint32_t>(i));
    }
    templates->Signal(SIGKILL);  // long before the periodic save: only the journal has them
    ASSERT_EQ(templates->WaitExit(5s), 128 + SIGKILL);
  }
  auto restarted = Start();
  for (int i = 0; i < kTemplates; ++i) {
    const auto view = Send(Scene(100 + i), 10 + i);
    ASSERT_TRUE(view) << restarted->Output();
    EXPECT_FALSE(view->is_new) << "template " << i << " was re-learnt";
    EXPECT_EQ(view->template_id, static_cast<uint32_t>(i));
    EXPECT_EQ(view->template_count, static_cast<uint32_t>(kTemplates));
  }
  const auto fresh_view = Send(Scene(999), 20);
  ASSERT_TRUE(fresh_view) << restarted->Output();
  EXPECT_TRUE(fresh_view->is_new);
  EXPECT_EQ(fresh_view->template_id, static_cast<uint32_t>(kTemplates)) << "ids continue, never reused";
}

TEST_F(TemplatesServiceTest, RestartAfterSigkillDropsATornJournalRecord) {
  {
    auto templates = Start();
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(Send(Scene(200 + i), i)) << templates->Output();
    templates->Signal(SIGKILL);
    ASSERT_EQ(templates->WaitExit(5s), 128 + SIGKILL);
  }
  // A record the kill cut short: a header promising more payload than there is.
  const std::filesystem::path journal = state_.path() / "templates.journal";
  ASSERT_TRUE(std::filesystem::exists(journal));
  {
    std::ofstream out(journal, std::ios::binary | std::ios::app);
    const char torn[] = {0x52, 0x53, 0x54, 0x4A, 0x40, 0x00, 0x00, 0x00, 0x11, 0x22, 0x33, 0x44, 0x0a};
    out.write(torn, sizeof torn);
  }
  auto restarted = Start();
  for (int i = 0; i < 3; ++i) {
    const auto view = Send(Scene(200 + i), 10 + i);
    ASSERT_TRUE(view) << restarted->Output();
    EXPECT_FALSE(view->is_new);
    EXPECT_EQ(view->template_id, static_cast<uint32_t>(i));
  }
  const auto next = Send(Scene(300), 20);
  ASSERT_TRUE(next) << restarted->Output();
  EXPECT_EQ(next->template_id, 3u);
}

TEST_F(TemplatesServiceTest, CleanStopAndRestartKeepsTemplates) {
  {
    auto templates = Start();
    for (int i = 0; i < 2; ++i) ASSERT_TRUE(Send(Scene(400 + i), i)) << templates->Output();
    templates->Signal(SIGTERM);
    ASSERT_EQ(templates->WaitExit(10s), 0) << templates->Output();
  }
  EXPECT_EQ(std::filesystem::file_size(state_.path() / "templates.journal"), 0u) << "saved in full on shutdown";
  auto restarted = Start();
  const auto view = Send(Scene(401), 5);
  ASSERT_TRUE(view) << restarted->Output();
  EXPECT_FALSE(view->is_new);
  EXPECT_EQ(view->template_id, 1u);
}

TEST_F(TemplatesServiceTest, PeriodicSaveMovesTheJournalIntoTheStateFile) {
  const std::filesystem::path journal = state_.path() / "templates.journal";
  // A short save period (Start() uses a long one).
  auto templates = std::make_unique<ChildProcess>(
      kBinary, std::vector<std::string>{"--domain", std::to_string(domain_.id()), "--state-dir",
                                        state_.path().string(), "--set", "service.heartbeat_period_s=0.1", "--set",
                                        "service.state_save_period_s=0.2", "--set", "templates.image_crop_x_min=0",
                                        "--set", "templates.image_crop_x_max=-1", "--set",
                                        "templates.image_crop_y_min=0", "--set", "templates.image_crop_y_max=-1",
                                        "--set", "templates.template_x_size=32", "--set",
                                        "templates.template_y_size=16", "--set", "templates.shift_match=4"});
  ASSERT_TRUE(testing::WaitFor([&] { return images_->MatchedSubscribers() >= 1; }, 10s)) << templates->Output();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(Send(Scene(500 + i), i)) << templates->Output();
  EXPECT_TRUE(testing::WaitFor([&] { return std::filesystem::file_size(journal) == 0; }, 5s))
      << "the periodic save empties the journal\n" << templates->Output();
  templates->Signal(SIGKILL);
  templates->WaitExit(5s);
  auto restarted = Start();
  const auto view = Send(Scene(502), 10);
  ASSERT_TRUE(view) << restarted->Output();
  EXPECT_FALSE(view->is_new);
  EXPECT_EQ(view->template_id, 2u);
  EXPECT_EQ(view->template_count, 3u);
}

TEST_F(TemplatesServiceTest, CorruptJournalBeforeItsLastRecordRefusesTheStart) {
  {
    std::ofstream out(state_.path() / "templates.journal", std::ios::binary);
    out << std::string(16, 'x') << std::string(200, 'y');  // not a record, and more data after it
  }
  const auto [code, output] = testing::RunToExit(
      kBinary, {"--domain", std::to_string(domain_.id()), "--state-dir", state_.path().string()});
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("templates.journal"), std::string::npos) << output;
}

TEST_F(TemplatesServiceTest, CorruptStateFileRefusesTheStart) {
  {
    std::ofstream out(state_.path() / "templates.pb", std::ios::binary);
    out << "RSLAMPB1 this is not a state file";
  }
  const auto [code, output] = testing::RunToExit(
      kBinary, {"--domain", std::to_string(domain_.id()), "--state-dir", state_.path().string()});
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("templates.pb"), std::string::npos) << output;
}

TEST_F(TemplatesServiceTest, BadConfigExitsTwoNamingTheKey) {
  const auto [code, output] =
      testing::RunToExit(kBinary, {"--domain", std::to_string(domain_.id()), "--set", "templates.mode=colour"});
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("templates.mode"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
