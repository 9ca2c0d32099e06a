// bench_pipeline: the six services behind the camera (odometry, templates, pose cells, experience
// map, occupancy, explorer) as separate processes on loopback DDS, fed 640x480 grey frames by this
// process (standing in for rslam-camera). Frames and map poses are counted on the RatSLAM chain;
// occupancy and explorer read the same frames and poses alongside, as they do in a deployment.
//   - throughput: frames pushed as fast as the pipeline takes them, losing none (at most
//     kWindow frames in flight between camera/image and experience_map/pose);
//   - latency: frames at 10 Hz, time from publishing camera/image to the experience map's
//     pose for that frame (p50/p99).
// range(0): 0 = Cyclone DDS, 1 = Fast DDS (every process).
//   build/bin/bench_pipeline --benchmark_format=json

#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <random>
#include <thread>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/support/test_domain.h"
#include "tools/launch/process_supervisor.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;

const char* Vendor(const benchmark::State& state) { return state.range(0) == 0 ? "cyclone" : "fastdds"; }

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// A textured strip the camera pans along: places repeat, so templates are matched and loops close.
class SyntheticCamera {
 public:
  SyntheticCamera() {
    cv::Mat noise(480, 2400, CV_8UC1);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> d(0, 255);
    for (int r = 0; r < noise.rows; ++r)
      for (int c = 0; c < noise.cols; ++c) noise.at<uint8_t>(r, c) = static_cast<uint8_t>(d(rng));
    cv::GaussianBlur(noise, strip_, cv::Size(0, 0), 6);
    cv::normalize(strip_, strip_, 0, 255, cv::NORM_MINMAX);
  }
  msg::Image Frame(uint64_t seq) const {
    msg::Image image;
    image.header = {"robot1", seq, static_cast<int64_t>(seq) * 100'000'000};
    image.width = 640;
    image.height = 480;
    image.encoding = "mono8";
    image.step = 640;
    image.data.resize(640 * 480);
    const int x0 = static_cast<int>((seq * 4) % static_cast<uint64_t>(strip_.cols - 640));
    for (int r = 0; r < 480; ++r) std::memcpy(&image.data[r * 640], strip_.ptr<uint8_t>(r) + x0, 640);
    return image;
  }

 private:
  cv::Mat strip_;
};

class Pipeline {
 public:
  Pipeline(const char* vendor, int domain) {
    const std::string bin = RSLAM_BINARY_DIR "/bin/";
    const std::string preset = RSLAM_SOURCE_DIR "/deploy/presets/stlucia.yaml";
    log_dir_ = std::filesystem::temp_directory_path() / ("rslam-bench-pipeline-" + std::to_string(::getpid()));
    std::filesystem::create_directories(log_dir_);
    for (const char* service : {"odometry", "templates", "pose-cells", "experience-map", "occupancy", "explorer"}) {
      launch::ProcessSpec spec;
      spec.name = service;
      spec.executable = bin + "rslam-" + service;
      spec.args = {"--config", preset, "--domain", std::to_string(domain), "--dds", vendor, "--log-level", "warn"};
      spec.log_file = (log_dir_ / (std::string(service) + ".log")).string();
      spec.restart = false;
      supervisor_.Start(spec);
    }
  }
  ~Pipeline() {
    supervisor_.StopAll();
    std::filesystem::remove_all(log_dir_);
  }

 private:
  launch::ProcessSupervisor supervisor_;
  std::filesystem::path log_dir_;
};

// Records when each frame's experience-map pose arrives.
class PoseWatcher {
 public:
  explicit PoseWatcher(bus::Participant& p)
      : sub_(p, bus::topics::kExperienceMapPose, [this](const msg::ExperiencePose& pose) {
          std::lock_guard lock(mutex_);
          last_seq_ = pose.header.frame_seq;
          arrivals_.push_back({pose.header.frame_seq, NowNs()});
          cv_.notify_all();
        }) {}
  bool WaitFor(uint64_t seq, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    return cv_.wait_for(lock, timeout, [&] { return last_seq_ != UINT64_MAX && last_seq_ >= seq; });
  }
  std::vector<std::pair<uint64_t, int64_t>> arrivals() {
    std::lock_guard lock(mutex_);
    return arrivals_;
  }
  bool Matched() const { return sub_.MatchedPublishers() >= 1; }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  uint64_t last_seq_ = UINT64_MAX;
  std::vector<std::pair<uint64_t, int64_t>> arrivals_;
  bus::Subscriber<msg::ExperiencePose> sub_;
};

struct Rig {
  explicit Rig(const char* vendor) : pipeline(vendor, domain.id()) {
    bus::BusConfig config;
    config.dds = vendor;
    config.domain_id = domain.id();
    participant = bus::Participant::Create(config);
    camera = std::make_unique<bus::Publisher<msg::Image>>(*participant, bus::topics::kCameraImage);
    poses = std::make_unique<PoseWatcher>(*participant);
  }
  bool Ready() {
    // Both image readers (odometry, templates) matched and the pose writer matched.
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (std::chrono::steady_clock::now() < deadline) {
      if (camera->MatchedSubscribers() >= 2 && poses->Matched()) return true;
      std::this_thread::sleep_for(20ms);
    }
    return false;
  }
  testing::TestDomain domain;
  Pipeline pipeline;
  std::unique_ptr<bus::Participant> participant;
  std::unique_ptr<bus::Publisher<msg::Image>> camera;
  std::unique_ptr<PoseWatcher> poses;
  SyntheticCamera frames;
};

void BM_PipelineThroughput(benchmark::State& state) {
  Rig rig(Vendor(state));
  if (!rig.Ready()) {
    state.SkipWithError("services did not come up (built? see their logs)");
    return;
  }
  constexpr uint64_t kFrames = 1500, kWindow = 4;
  std::vector<msg::Image> images;
  for (uint64_t i = 0; i < kFrames; ++i) images.push_back(rig.frames.Frame(i));
  uint64_t total = 0;
  for (auto _ : state) {
    for (uint64_t i = 0; i < kFrames; ++i) {
      if (i >= kWindow && !rig.poses->WaitFor(i - kWindow, 10s)) {
        state.SkipWithError("a frame was lost in the pipeline");
        return;
      }
      rig.camera->Publish(images[i]);
    }
    if (!rig.poses->WaitFor(kFrames - 1, 10s)) {
      state.SkipWithError("the last frame never reached the experience map");
      return;
    }
    total += kFrames;
  }
  state.SetItemsProcessed(static_cast<int64_t>(total));
  state.SetLabel(std::string(Vendor(state)) + ", 640x480 mono8, six services");
}

void BM_PipelineLatency10Hz(benchmark::State& state) {
  Rig rig(Vendor(state));
  if (!rig.Ready()) {
    state.SkipWithError("services did not come up (built? see their logs)");
    return;
  }
  std::vector<int64_t> sent;
  uint64_t seq = 0;
  auto next = std::chrono::steady_clock::now();
  // Warm up until the pipeline answers: a fresh pose-cell service first waits up to
  // resync_timeout_s (3 s) for an experience map to resume from.
  while (seq < 100) {
    next += 100ms;
    std::this_thread::sleep_until(next);
    sent.push_back(NowNs());
    rig.camera->Publish(rig.frames.Frame(seq++));
    if (rig.poses->WaitFor(0, 0ms) && seq >= 10) break;
  }
  if (!rig.poses->WaitFor(seq - 1, 10s)) {
    state.SkipWithError("the pipeline did not answer during warm-up");
    return;
  }
  const uint64_t first_measured = seq;
  for (auto _ : state) {
    next += 100ms;
    std::this_thread::sleep_until(next);  // the 10 Hz camera of the measurement
    msg::Image image = rig.frames.Frame(seq);
    sent.push_back(NowNs());
    rig.camera->Publish(image);
    ++seq;
  }
  if (!rig.poses->WaitFor(seq - 1, 10s)) {
    state.SkipWithError("frames lost");
    return;
  }
  std::vector<double> latency_ms;
  for (const auto& [frame, at] : rig.poses->arrivals())
    if (frame >= first_measured && frame < sent.size()) latency_ms.push_back(static_cast<double>(at - sent[frame]) / 1e6);
  std::sort(latency_ms.begin(), latency_ms.end());
  state.counters["p50_ms"] = latency_ms[latency_ms.size() / 2];
  state.counters["p99_ms"] = latency_ms[std::min(latency_ms.size() - 1, latency_ms.size() * 99 / 100)];
  state.counters["frames"] = static_cast<double>(latency_ms.size());
  state.SetLabel(Vendor(state));
}

BENCHMARK(BM_PipelineThroughput)->DenseRange(0, 1)->Iterations(1)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PipelineLatency10Hz)->DenseRange(0, 1)->Iterations(300)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rslam
