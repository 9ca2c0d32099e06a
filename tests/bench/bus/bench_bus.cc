// bench_bus: the bus between two processes over loopback, on each vendor and across vendors.
//   build/bin/bench_bus --benchmark_format=json      (tools/bench-bus.sh adds ddsperf beside it)
//
// BM_LatencySmall, BM_LatencyImage (a Velocity message, a 640x480 mono8 image): ping-pong with a
// peer process (bench_bus_peer.h), one message in flight, as Cyclone's ddsperf ping/pong.
// "writer->reader" names the ping direction: this process writes with the first vendor, the peer
// reads with the second and echoes back with it. Counters:
//   p50_us, p99_us            one-way latency writer->reader (publish to the reader's hands;
//                             both processes read the same monotonic clock)
//   back_p50_us               one-way latency of the echo (reader's vendor -> writer's vendor)
//   half_rtt_p50_us, _p99_us  half the round trip, what ddsperf reports: compare these with it
//   cdr_bytes                 serialized size (4-byte encapsulation header included)
// BM_ImageThroughput: lossless images (reliable keep-all, the writer blocks while the reader
// lags) from this process to a peer that acknowledges every kAckEvery-th; items_per_second.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "common/bus/typed_cdr.h"
#include "tests/bench/bus/bench_bus_peer.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam::bus::bench {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr Vendor kVendors[] = {Vendor::kCyclone, Vendor::kFastDds};

std::unique_ptr<Participant> Make(Vendor vendor, int domain) {
  BusConfig config;
  config.dds = VendorName(vendor);
  config.domain_id = domain;
  return Participant::Create(config);
}

std::string PairName(Vendor writer, Vendor reader) { return std::string(VendorName(writer)) + "->" + VendorName(reader); }

// The peer process, stopped (SIGTERM) and reaped with the object.
testing::ChildProcess StartPeer(PeerRole role, Vendor vendor, int domain) {
  return testing::ChildProcess(std::filesystem::read_symlink("/proc/self/exe").string(),
                               PeerArguments(role, vendor, domain));
}

msg::Velocity MakeSmall() {
  msg::Velocity v;
  v.header.robot_id = "robot1";
  v.vtrans_mps = 0.5;
  v.vrot_radps = 0.1;
  v.dt_s = 0.1;
  return v;
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

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<std::size_t>(q * static_cast<double>(values.size())))];
}

// Any failure ends the benchmark with an error (never the process): a BusError from a blocked
// writer, a lost message, a peer that did not start.
void Guarded(benchmark::State& state, const std::function<void()>& body) {
  try {
    body();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

struct RoundTripTimes {
  double forward_us;  // ping: writer -> reader
  double back_us;     // pong: reader -> writer
  double rtt_us;
};

template <class T>
void MeasureRoundTrips(benchmark::State& state, Vendor writer, Vendor reader, PeerRole role,
                       const Topic<T>& ping_topic, const Topic<T>& pong_topic, T message, const char* payload) {
  testing::TestDomain domain;
  testing::ChildProcess peer = StartPeer(role, reader, domain.id());
  auto participant = Make(writer, domain.id());
  Publisher<T> ping(*participant, ping_topic);
  Subscriber<T> pong(*participant, pong_topic);  // taken on this thread, as ddsperf's waitset mode
  if (!ping.WaitForSubscribers(1, 20s) || !pong.WaitForPublishers(1, 20s)) {
    state.SkipWithError(("the peer did not match\n" + peer.Tail()).c_str());
    return;
  }
  uint64_t seq = 0;
  // One round trip; nothing if no answer within timeout. Older answers (to pings that timed out
  // during the warm-up) are skipped.
  auto round_trip = [&](std::chrono::milliseconds timeout) -> std::optional<RoundTripTimes> {
    const uint64_t want = seq++;
    message.header.frame_seq = want;
    const int64_t sent_ns = SteadyNowNs();
    message.header.stamp_ns = sent_ns;
    ping.Publish(message);
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()) + 1ms;
      std::optional<T> answer = pong.TakeOne(left);
      const int64_t now_ns = SteadyNowNs();
      if (answer && answer->header.frame_seq == want) {
        return RoundTripTimes{(answer->header.stamp_ns - sent_ns) / 1e3, (now_ns - answer->header.stamp_ns) / 1e3,
                              (now_ns - sent_ns) / 1e3};
      }
    }
    return std::nullopt;
  };
  // Warm-up: the peer may match us a little after we match it (a ping before that is lost, so
  // retry), and the first samples pay for allocations.
  int warm = 0;
  for (const auto give_up = Clock::now() + 20s; warm < 100 && Clock::now() < give_up;)
    if (round_trip(1s)) ++warm;
  if (warm < 100) {
    state.SkipWithError(("no answers from the peer\n" + peer.Tail()).c_str());
    return;
  }
  std::vector<double> forward, back, half_rtt;
  for (auto _ : state) {
    const std::optional<RoundTripTimes> t = round_trip(5s);
    if (!t) {
      state.SkipWithError("a ping or its echo was lost (no answer within 5 s)");
      break;
    }
    forward.push_back(t->forward_us);
    back.push_back(t->back_us);
    half_rtt.push_back(t->rtt_us / 2);
  }
  state.counters["p50_us"] = Percentile(forward, 0.50);
  state.counters["p99_us"] = Percentile(forward, 0.99);
  state.counters["back_p50_us"] = Percentile(back, 0.50);
  state.counters["half_rtt_p50_us"] = Percentile(half_rtt, 0.50);
  state.counters["half_rtt_p99_us"] = Percentile(half_rtt, 0.99);
  state.counters["cdr_bytes"] = static_cast<double>(ToCdr(message).size());
  state.SetLabel(PairName(writer, reader) + " " + payload);
}

void BM_LatencySmall(benchmark::State& state, Vendor writer, Vendor reader) {
  Guarded(state, [&] {
    MeasureRoundTrips(state, writer, reader, PeerRole::kEchoSmall, kPingSmall, kPongSmall, MakeSmall(),
                      "Velocity, stream QoS");
  });
}

void BM_LatencyImage(benchmark::State& state, Vendor writer, Vendor reader) {
  Guarded(state, [&] {
    MeasureRoundTrips(state, writer, reader, PeerRole::kEchoImage, kPingImage, kPongImage, MakeImage(),
                      "640x480 mono8, sensor QoS");
  });
}

void MeasureThroughput(benchmark::State& state, Vendor writer, Vendor reader) {
  testing::TestDomain domain;
  testing::ChildProcess peer = StartPeer(PeerRole::kSinkImages, reader, domain.id());
  auto participant = Make(writer, domain.id());
  Publisher<msg::Image> images(*participant, kImageStream);
  Subscriber<msg::Velocity> acks(*participant, kStreamAck);
  if (!images.WaitForSubscribers(1, 20s) || !acks.WaitForPublishers(1, 20s)) {
    state.SkipWithError(("the peer did not match\n" + peer.Tail()).c_str());
    return;
  }
  msg::Image image = MakeImage();
  uint64_t seq = 0;
  // Waits for the acknowledgment of frame `last`; returns the sink's count then, or nothing.
  auto await_ack = [&](uint64_t last, std::chrono::milliseconds timeout) -> std::optional<uint64_t> {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()) + 1ms;
      if (std::optional<msg::Velocity> ack = acks.TakeOne(left); ack && ack->header.frame_seq == last)
        return static_cast<uint64_t>(ack->header.stamp_ns);
    }
    return std::nullopt;
  };
  // Warm-up: single acknowledged images until the peer answers (it may match us a little after
  // we match it), then one batch.
  std::optional<uint64_t> counted;
  for (const auto give_up = Clock::now() + 20s; !counted && Clock::now() < give_up;) {
    seq += kAckEvery - seq % kAckEvery;  // an acknowledged frame_seq
    image.header.frame_seq = seq - 1;
    images.Publish(image);
    counted = await_ack(seq - 1, 200ms);
  }
  if (!counted) {
    state.SkipWithError(("no acknowledgment from the peer\n" + peer.Tail()).c_str());
    return;
  }
  constexpr uint64_t kBatch = 4 * kAckEvery;
  uint64_t sent = 0;
  for (auto _ : state) {
    for (uint64_t i = 0; i < kBatch; ++i) {
      image.header.frame_seq = seq++;
      images.Publish(image);
    }
    sent += kBatch;
    const std::optional<uint64_t> count = await_ack(seq - 1, 30s);
    if (!count || *count != *counted + sent) {
      state.SkipWithError(count ? "images lost" : "no acknowledgment within 30 s");
      break;
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(sent));
  state.SetBytesProcessed(static_cast<int64_t>(sent * image.data.size()));
  state.SetLabel(PairName(writer, reader) + " 640x480 mono8, stream QoS (reliable keep-all)");
}

void BM_ImageThroughput(benchmark::State& state, Vendor writer, Vendor reader) {
  Guarded(state, [&] { MeasureThroughput(state, writer, reader); });
}

void RegisterAll() {
  for (Vendor writer : kVendors)
    for (Vendor reader : kVendors)
      benchmark::RegisterBenchmark(("BM_LatencySmall/" + PairName(writer, reader)).c_str(), BM_LatencySmall, writer,
                                   reader)
          ->Iterations(2000)->UseRealTime()->Unit(benchmark::kMicrosecond);
  for (Vendor writer : kVendors)
    for (Vendor reader : kVendors)
      benchmark::RegisterBenchmark(("BM_LatencyImage/" + PairName(writer, reader)).c_str(), BM_LatencyImage, writer,
                                   reader)
          ->Iterations(500)->UseRealTime()->Unit(benchmark::kMicrosecond);
  for (Vendor writer : kVendors)
    for (Vendor reader : kVendors)
      benchmark::RegisterBenchmark(("BM_ImageThroughput/" + PairName(writer, reader)).c_str(), BM_ImageThroughput,
                                   writer, reader)
          ->Iterations(5)->UseRealTime()->Unit(benchmark::kMillisecond);
}

}  // namespace
}  // namespace rslam::bus::bench

int main(int argc, char** argv) {
  using namespace rslam::bus::bench;
  if (IsPeerCommandLine(argc, argv)) return RunPeer(argc, argv);
  RegisterAll();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
