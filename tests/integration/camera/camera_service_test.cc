// rslam-camera as a black box on a private DDS domain: image folders, pacing, the simulator
// source, and how it fails.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <chrono>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "services/occupancy/camera_model.h"
#include "tests/integration/camera/image_test_util.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::ScratchFolder;
using testing::WaitFor;

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-camera";

class CameraServiceTest : public ::testing::Test {
 protected:
  CameraServiceTest() {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
  }

  // count PNG files frame_000.png ... of distinct random textures; returns the images.
  std::vector<cv::Mat> WriteImages(int count, int width = 64, int height = 48) {
    std::vector<cv::Mat> images;
    for (int i = 0; i < count; ++i) {
      images.push_back(testing::RandomTexture(width, height, 3, 1000 + i));
      char name[32];
      std::snprintf(name, sizeof name, "frame_%03d.png", i);
      EXPECT_TRUE(cv::imwrite((images_.path() / name).string(), images.back()));
    }
    return images;
  }

  // No pipeline runs in these tests: no lockstep unless a test asks for it (later --set wins).
  std::vector<std::string> Args(std::vector<std::string> extra) const {
    std::vector<std::string> args{"--domain", std::to_string(domain_.id()), "--set",
                                  "service.heartbeat_period_s=0.2", "--set", "camera.lockstep_topics=[]"};
    for (auto& e : extra) {
      args.push_back("--set");
      args.push_back("camera." + e);
    }
    return args;
  }

  testing::TestDomain domain_;
  ScratchFolder images_;
  std::unique_ptr<bus::Participant> participant_;
};

TEST_F(CameraServiceTest, ImageFolderFramesArriveInOrderWithDeterministicStampsThenTheServiceExits) {
  const std::vector<cv::Mat> images = WriteImages(6);
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "fps=5",
                                       "start_stamp_ns=1000000000", "rate_hz=0", "wait_for_readers=1"}));
  for (int i = 0; i < 6; ++i) {
    const auto frame = frames.TakeOne(10s);
    ASSERT_TRUE(frame) << "frame " << i << "\n" << camera.Output();
    EXPECT_EQ(frame->header.robot_id, "robot1");
    EXPECT_EQ(frame->header.frame_seq, static_cast<uint64_t>(i));
    EXPECT_EQ(frame->header.stamp_ns, 1'000'000'000 + i * 200'000'000LL) << "stamps come from the source rate";
    EXPECT_EQ(frame->encoding, "bgr8");
    ASSERT_EQ(frame->width, 64u);
    ASSERT_EQ(frame->height, 48u);
    EXPECT_EQ(cv::norm(camera::ImageView(*frame), images[i], cv::NORM_INF), 0) << "frame " << i;
  }
  EXPECT_EQ(camera.WaitExit(10s), 0) << "end of a finite source is a clean exit\n" << camera.Output();
  EXPECT_NE(camera.Output().find("end of"), std::string::npos) << camera.Output();
  EXPECT_FALSE(frames.TakeOne(200ms)) << "nothing after the last frame";
}

TEST_F(CameraServiceTest, RateZeroInLockstepLosesNothingForAStageThatFallsBehind) {
  constexpr int kFrames = 30;  // far more than the sensor preset's keep-last depth (8)
  WriteImages(kFrames, 32, 24);
  // The test is a pipeline stage: it takes frames slowly and reports each on odometry/velocity.
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  bus::Publisher<msg::Velocity> done(*participant_, bus::topics::kOdometryVelocity);
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "rate_hz=0",
                                       "lockstep_topics=[odometry/velocity]", "max_frames_in_flight=4"}));
  ASSERT_TRUE(frames.WaitForPublishers(1, 10s)) << camera.Output();
  ASSERT_TRUE(done.WaitForSubscribers(1, 10s)) << camera.Output();
  std::this_thread::sleep_for(1s);  // falls far behind at first: the camera must wait for it
  std::vector<uint64_t> seqs;
  while (seqs.size() < kFrames) {
    const auto frame = frames.TakeOne(10s);
    if (!frame) break;
    seqs.push_back(frame->header.frame_seq);
    std::this_thread::sleep_for(20ms);  // slower than the camera could go
    msg::Velocity v;
    v.header = frame->header;
    done.Publish(v);
  }
  ASSERT_EQ(seqs.size(), static_cast<std::size_t>(kFrames)) << camera.Output();
  for (int i = 0; i < kFrames; ++i) EXPECT_EQ(seqs[i], static_cast<uint64_t>(i));
}

TEST_F(CameraServiceTest, TheFirstFrameWaitsForTheNamedServicesHeartbeatsOrSaysWhatIsMissing) {
  WriteImages(2);
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  {
    // Nobody named `ping` runs yet: the camera waits out its timeout, then starts and says why.
    ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "rate_hz=0",
                                         "wait_for_services=[ping]", "wait_for_readers_timeout_s=1"}));
    ASSERT_TRUE(frames.TakeOne(10s)) << camera.Output();
    EXPECT_NE(camera.Output().find("starting anyway: no heartbeat from ping yet"), std::string::npos)
        << camera.Output();
    EXPECT_EQ(camera.WaitExit(10s), 0) << camera.Output();
  }
  while (frames.TakeOne(100ms)) {
  }
  // `rslam ping` heartbeats as service `ping`: the camera starts once it is heard and linked.
  ChildProcess ping(RSLAM_BINARY_DIR "/bin/rslam", {"ping", "--domain", std::to_string(domain_.id()), "--seconds", "30"});
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "rate_hz=0",
                                       "wait_for_services=[ping]", "wait_for_readers_timeout_s=20"}));
  ASSERT_TRUE(frames.TakeOne(20s)) << camera.Output() << ping.Output();
  EXPECT_EQ(camera.WaitExit(10s), 0) << camera.Output();
  EXPECT_EQ(camera.Output().find("starting anyway"), std::string::npos) << camera.Output();
}

TEST_F(CameraServiceTest, UnreadableImageIsSkippedAndCountedAndItsNumberStaysUnused) {
  WriteImages(4);
  {
    std::ofstream broken(images_.path() / "frame_002.png", std::ios::trunc);
    broken << "not a png";
  }
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  bus::Subscriber<msg::ServiceStatus> heartbeats(*participant_, bus::topics::kStatus);
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "fps=10"}));
  for (const uint64_t expected : {0u, 1u, 3u}) {
    const auto frame = frames.TakeOne(10s);
    ASSERT_TRUE(frame) << camera.Output();
    EXPECT_EQ(frame->header.frame_seq, expected);
    EXPECT_EQ(frame->header.stamp_ns, static_cast<int64_t>(expected) * 100'000'000);
  }
  EXPECT_TRUE(testing::AwaitHeartbeat(heartbeats, "camera",
                                      [](const msg::ServiceStatus& s) { return s.messages_rejected >= 1; }, 5s))
      << camera.Output();
  EXPECT_NE(camera.Output().find("frame_002.png"), std::string::npos) << camera.Output();
}

TEST_F(CameraServiceTest, LoopContinuesFrameNumbersAndStampsUpwards) {
  const std::vector<cv::Mat> images = WriteImages(3);
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "fps=10", "loop=true",
                                       "rate_hz=50"}));
  for (int i = 0; i < 8; ++i) {
    const auto frame = frames.TakeOne(10s);
    ASSERT_TRUE(frame) << "frame " << i << "\n" << camera.Output();
    EXPECT_EQ(frame->header.frame_seq, static_cast<uint64_t>(i));
    EXPECT_EQ(frame->header.stamp_ns, i * 100'000'000LL) << "stamps from the source rate, not rate_hz";
    EXPECT_EQ(cv::norm(camera::ImageView(*frame), images[i % 3], cv::NORM_INF), 0) << "frame " << i;
  }
  EXPECT_TRUE(camera.Running()) << "a looping source does not end";
}

TEST_F(CameraServiceTest, VideoFileFramesArriveInOrderWithIncreasingStamps) {
  const std::string video = (images_.path() / "clip.avi").string();
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(64, 48));
    if (!writer.isOpened()) GTEST_SKIP() << "OpenCV cannot write MJPG video here";
    for (int i = 0; i < 5; ++i) writer.write(testing::RandomTexture(64, 48, 3, 50 + i));
  }
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  ChildProcess camera(kBinary, Args({"source=video", "path=" + video}));
  int64_t previous_stamp = -1;
  for (int i = 0; i < 5; ++i) {
    const auto frame = frames.TakeOne(10s);
    ASSERT_TRUE(frame) << "frame " << i << "\n" << camera.Output();
    EXPECT_EQ(frame->header.frame_seq, static_cast<uint64_t>(i));
    EXPECT_GT(frame->header.stamp_ns, previous_stamp);
    previous_stamp = frame->header.stamp_ns;
    EXPECT_EQ(frame->width, 64u);
  }
  EXPECT_EQ(camera.WaitExit(10s), 0) << camera.Output();
}

TEST_F(CameraServiceTest, CropAndGreyAreApplied) {
  const std::vector<cv::Mat> images = WriteImages(2);
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "crop.x=8", "crop.y=4",
                                       "crop.width=20", "crop.height=10", "grey=true"}));
  const auto frame = frames.TakeOne(10s);
  ASSERT_TRUE(frame) << camera.Output();
  EXPECT_EQ(frame->encoding, "mono8");
  ASSERT_EQ(frame->width, 20u);
  ASSERT_EQ(frame->height, 10u);
  cv::Mat expected;
  cv::cvtColor(images[0](cv::Rect(8, 4, 20, 10)), expected, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(camera::ImageView(*frame), expected, cv::NORM_INF), 0);
}

TEST_F(CameraServiceTest, AntiVignettingAndUndistortionMatchTheOccupancyCameraModel) {
  const std::vector<cv::Mat> images = WriteImages(1);
  occupancy::CameraConfig model;
  model.width = 64;
  model.height = 48;
  model.fx = model.fy = 50.0;
  model.cx = 31.5;
  model.cy = 23.5;
  model.k1 = -0.2;
  model.vignetting_gains = {0.3, 0.2, 0.1};
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  ChildProcess camera(kBinary, Args({"source=images", "path=" + images_.path().string(), "anti_vignetting=true",
                                       "undistort=true", "model.width=64", "model.height=48", "model.fx=50",
                                       "model.fy=50", "model.cx=31.5", "model.cy=23.5", "model.k1=-0.2",
                                       "model.vignetting_gains=[0.3, 0.2, 0.1]"}));
  const auto frame = frames.TakeOne(10s);
  ASSERT_TRUE(frame) << camera.Output();
  const cv::Mat expected = occupancy::CameraModel(model).Correct(images[0]);
  EXPECT_GT(cv::norm(expected, images[0], cv::NORM_L1), 0) << "the correction changes the image";
  EXPECT_EQ(cv::norm(camera::ImageView(*frame), expected, cv::NORM_INF), 0);
}

TEST_F(CameraServiceTest, CropOutsideTheImageIsAConfigErrorNamingCrop) {
  WriteImages(1);
  const auto [code, output] = testing::RunToExit(
      kBinary, Args({"source=images", "path=" + images_.path().string(), "crop.x=60", "crop.width=20"}));
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("crop"), std::string::npos) << output;
}

TEST_F(CameraServiceTest, SimSourceRepublishesSimulatorFramesWithTheirSeqAndStamp) {
  bus::Publisher<msg::Image> sim(*participant_, bus::topics::kSimCamera);
  bus::Subscriber<msg::Image> frames(*participant_, bus::topics::kCameraImage);
  ChildProcess camera(kBinary, Args({"source=sim"}));
  ASSERT_TRUE(sim.WaitForSubscribers(1, 10s)) << camera.Output();
  ASSERT_TRUE(frames.WaitForPublishers(1, 10s)) << camera.Output();
  for (uint64_t seq = 100; seq < 104; ++seq) {
    const cv::Mat image = testing::RandomTexture(40, 30, 3, seq);
    sim.Publish(testing::ImageMessage(image, seq, 5'000'000'000LL + static_cast<int64_t>(seq) * 1'000'000));
    const auto frame = frames.TakeOne(5s);
    ASSERT_TRUE(frame) << "sim frame " << seq << "\n" << camera.Output();
    EXPECT_EQ(frame->header.frame_seq, seq);
    EXPECT_EQ(frame->header.stamp_ns, 5'000'000'000LL + static_cast<int64_t>(seq) * 1'000'000);
    EXPECT_EQ(cv::norm(camera::ImageView(*frame), image, cv::NORM_INF), 0);
  }
  // A malformed sim frame is dropped and counted; the next good one still goes through.
  bus::Subscriber<msg::ServiceStatus> heartbeats(*participant_, bus::topics::kStatus);
  msg::Image bad = testing::ImageMessage(testing::RandomTexture(40, 30, 3, 1), 104, 6'000'000'000LL);
  bad.data.resize(10);
  sim.Publish(bad);
  sim.Publish(testing::ImageMessage(testing::RandomTexture(40, 30, 3, 2), 105, 6'100'000'000LL));
  const auto after = frames.TakeOne(5s);
  ASSERT_TRUE(after) << camera.Output();
  EXPECT_EQ(after->header.frame_seq, 105u);
  EXPECT_TRUE(testing::AwaitHeartbeat(heartbeats, "camera",
                                      [](const msg::ServiceStatus& s) { return s.messages_rejected >= 1; }, 5s))
      << camera.Output();
}

TEST_F(CameraServiceTest, MissingDeviceExitsOneNamingTheDevice) {
  const auto [code, output] = testing::RunToExit(kBinary, Args({"source=device", "device=/dev/video-rslam-absent"}));
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("/dev/video-rslam-absent"), std::string::npos) << output;
}

TEST_F(CameraServiceTest, BadConfigExitsTwoNamingTheKey) {
  const auto [code, output] = testing::RunToExit(kBinary, Args({"source=images", "path=/tmp", "rate_hz=-3"}));
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("camera.rate_hz"), std::string::npos) << output;
}

TEST_F(CameraServiceTest, ImagesSourceWithoutPathExitsTwoNamingPath) {
  const auto [code, output] = testing::RunToExit(kBinary, Args({"source=images"}));
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("camera.path"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
