// Real frames through the front of the pipeline: rslam-camera reads the iRat sample frames
// (/work/shared/data/irat, 416x240) and feeds rslam-odometry and rslam-templates configured by
// the iRat preset. Skipped when the shared data is absent.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/subscriber.h"
#include "services/camera/frame_source.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;

const std::string kBin = RSLAM_BINARY_DIR "/bin/";
const std::string kPreset = RSLAM_SOURCE_DIR "/deploy/presets/irat.yaml";

TEST(IratPipelineTest, EveryFrameGetsOneVelocityAndOneViewInOrder) {
  const std::string data = testing::SharedDataDir();
  if (data.empty() || !std::filesystem::is_directory(data + "/irat")) GTEST_SKIP() << "no shared iRat frames";
  const std::string folder = data + "/irat";
  const std::size_t frames = camera::ListImages(folder).size();
  ASSERT_GT(frames, 1u);

  testing::TestDomain domain;
  bus::BusConfig config;
  config.domain_id = domain.id();
  auto participant = bus::Participant::Create(config);
  bus::Subscriber<msg::Velocity> velocities(*participant, bus::topics::kOdometryVelocity);
  bus::Subscriber<msg::ViewTemplate> views(*participant, bus::topics::kTemplatesView);
  const std::vector<std::string> common{"--domain", std::to_string(domain.id()), "--config", kPreset};

  ChildProcess odometry(kBin + "rslam-odometry", common);
  ChildProcess templates(kBin + "rslam-templates", common);
  ASSERT_TRUE(velocities.WaitForPublishers(1, 10s)) << odometry.Output();
  ASSERT_TRUE(views.WaitForPublishers(1, 10s)) << templates.Output();
  std::vector<std::string> camera_args = common;
  for (const std::string kv : {"source=images", "fps=10", "rate_hz=0", "wait_for_readers=2"}) {
    camera_args.push_back("--set");
    camera_args.push_back("camera." + kv);
  }
  camera_args.push_back("--set");
  camera_args.push_back("camera.path=" + folder);
  ChildProcess camera(kBin + "rslam-camera", camera_args);

  uint32_t templates_seen = 0;
  for (std::size_t i = 0; i < frames; ++i) {
    const auto v = velocities.TakeOne(10s);
    ASSERT_TRUE(v) << "velocity " << i << "\n" << camera.Output() << odometry.Output();
    EXPECT_EQ(v->header.frame_seq, i);
    EXPECT_EQ(v->header.stamp_ns, static_cast<int64_t>(i) * 100'000'000);
    EXPECT_NEAR(v->dt_s, i == 0 ? 0.0 : 0.1, 1e-12);
    EXPECT_TRUE(std::isfinite(v->vrot_radps));
    EXPECT_GE(v->vtrans_mps, 0.0);
    EXPECT_LE(v->vtrans_mps, 0.5) << "the preset's vtrans_max";

    const auto view = views.TakeOne(10s);
    ASSERT_TRUE(view) << "view " << i << "\n" << camera.Output() << templates.Output();
    EXPECT_EQ(view->header.frame_seq, i);
    EXPECT_EQ(view->header.stamp_ns, v->header.stamp_ns);
    EXPECT_TRUE(std::isfinite(view->difference));
    if (view->is_new) {
      EXPECT_EQ(view->template_id, templates_seen) << "ids are dense, in learning order";
      ++templates_seen;
    } else {
      EXPECT_LT(view->template_id, templates_seen);
    }
    EXPECT_EQ(view->template_count, templates_seen);
  }
  EXPECT_EQ(camera.WaitExit(10s), 0) << camera.Output();
}

}  // namespace
}  // namespace rslam
