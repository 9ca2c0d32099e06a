// bench_bus: one-way latency (p50/p99) for a small message and a 640x480 mono8 image, and
// lossless image throughput, on each vendor and across vendors, over loopback.
//   build/bin/bench_bus --benchmark_format=json
// Compare with Cyclone's own path: tools/bench-bus.sh runs ddsperf beside this.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/support/test_domain.h"

namespace rslam::bus {
namespace {

using namespace std::chrono_literals;

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::unique_ptr<Participant> Make(Vendor vendor, int domain) {
  BusConfig config;
  config.dds = VendorName(vendor);
  config.domain_id = domain;
  return Participant::Create(config);
}

Vendor WriterOf(const benchmark::State& state) { return state.range(0) / 2 ? Vendor::kFastDds : Vendor::kCyclone; }
Vendor ReaderOf(const benchmark::State& state) { return state.range(0) % 2 ? Vendor::kFastDds : Vendor::kCyclone; }

void Label(benchmark::State& state, const char* payload) {
  state.SetLabel(std::string(VendorName(WriterOf(state))) + "->" + VendorName(ReaderOf(state)) + " " + payload);
}

msg::Image MakeImage() {
  msg::Image image;
  image.header.robot_id = "robot1";
  image.width = 640;
  image.height = 480;
  image.encoding = "mono8";
  image.step = 640;
  image.data.resize(640 * 480);
  for (std::size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(i * 7);
  return image;
}

// One message in flight at a time: publish, wait until the reader's callback has it.
template <class T>
void MeasureLatency(benchmark::State& state, T message, const Topic<T>& topic, const char* payload) {
  testing::TestDomain domain;
  auto writer_pp = Make(WriterOf(state), domain.id());
  auto reader_pp = Make(ReaderOf(state), domain.id());
  std::mutex mutex;
  std::condition_variable cv;
  uint64_t received_seq = UINT64_MAX;
  std::vector<double> latencies_us;
  Subscriber<T> sub(*reader_pp, topic, [&](const T& m) {
    const double us = static_cast<double>(NowNs() - m.header.stamp_ns) / 1000.0;
    std::lock_guard lock(mutex);
    latencies_us.push_back(us);
    received_seq = m.header.frame_seq;
    cv.notify_one();
  });
  Publisher<T> pub(*writer_pp, topic);
  if (!pub.WaitForSubscribers(1, 10s) || !sub.WaitForPublishers(1, 10s)) {
    state.SkipWithError("endpoints did not match");
    return;
  }
  // Warm up (first samples pay for allocations and ARP-free loopback paths).
  uint64_t seq = 0;
  auto send_and_wait = [&] {
    message.header.frame_seq = seq;
    message.header.stamp_ns = NowNs();
    pub.Publish(message);
    std::unique_lock lock(mutex);
    const uint64_t want = seq++;
    return cv.wait_for(lock, 5s, [&] { return received_seq == want; });
  };
  for (int i = 0; i < 50; ++i) send_and_wait();
  {
    std::lock_guard lock(mutex);
    latencies_us.clear();
  }
  for (auto _ : state) {
    if (!send_and_wait()) {
      state.SkipWithError("message lost");
      return;
    }
  }
  std::lock_guard lock(mutex);
  std::sort(latencies_us.begin(), latencies_us.end());
  if (latencies_us.empty()) return;
  state.counters["p50_us"] = latencies_us[latencies_us.size() / 2];
  state.counters["p99_us"] = latencies_us[std::min(latencies_us.size() - 1, latencies_us.size() * 99 / 100)];
  state.counters["max_us"] = latencies_us.back();
  Label(state, payload);
}

void BM_LatencySmall(benchmark::State& state) {
  msg::Velocity v;
  v.header.robot_id = "robot1";
  MeasureLatency(state, v, topics::kOdometryVelocity, "Velocity (72 B)");
}

void BM_LatencyImage(benchmark::State& state) {
  MeasureLatency(state, MakeImage(), Topic<msg::Image>{"bench/image", QosPreset::kStream}, "640x480 mono8");
}

// Lossless throughput: reliable keep-all, the writer blocks when the reader falls behind.
void BM_ImageThroughput(benchmark::State& state) {
  testing::TestDomain domain;
  auto writer_pp = Make(WriterOf(state), domain.id());
  auto reader_pp = Make(ReaderOf(state), domain.id());
  const Topic<msg::Image> topic{"bench/image_stream", QosPreset::kStream};
  std::atomic<uint64_t> received{0};
  Subscriber<msg::Image> sub(*reader_pp, topic, [&](const msg::Image&) { ++received; });
  Publisher<msg::Image> pub(*writer_pp, topic);
  if (!pub.WaitForSubscribers(1, 10s) || !sub.WaitForPublishers(1, 10s)) {
    state.SkipWithError("endpoints did not match");
    return;
  }
  msg::Image image = MakeImage();
  constexpr int kBatch = 500;
  uint64_t sent = 0;
  for (auto _ : state) {
    for (int i = 0; i < kBatch; ++i) {
      image.header.frame_seq = sent++;
      pub.Publish(image);
    }
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (received < sent && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(50us);
    if (received < sent) {
      state.SkipWithError("images lost");
      return;
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(sent));
  state.SetBytesProcessed(static_cast<int64_t>(sent * image.data.size()));
  Label(state, "640x480 mono8, reliable keep-all");
}

// range(0): 0 cyclone->cyclone, 1 cyclone->fastdds, 2 fastdds->cyclone, 3 fastdds->fastdds
BENCHMARK(BM_LatencySmall)->DenseRange(0, 3)->Iterations(2000)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LatencyImage)->DenseRange(0, 3)->Iterations(500)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ImageThroughput)->DenseRange(0, 3)->Iterations(4)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rslam::bus
