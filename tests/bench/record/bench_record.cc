// bench_record: how fast `rslam record` stores 640x480 colour images arriving over the bus
// (target >= 100 MB/s with zstd on one core, nothing dropped), what the storage side alone
// costs, and how many messages per second `rslam play --max` delivers to a subscriber.
//
// Images: a real iRat camera frame (shared data, 416x240 scaled to 640x480) with a little
// per-frame sensor noise, so zstd sees camera-like content; synthetic gradients if the shared
// data is absent (the label says which).
#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "common/bus/topics.h"
#include "common/bus/typed_cdr.h"
#include "tests/support/test_domain.h"
#include "tools/record/player.h"
#include "tools/record/recorder.h"

namespace rslam::record {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

struct ImageSource {
  cv::Mat base;  // 640x480 bgr8
  bool real = false;
};

const ImageSource& Source() {
  static const ImageSource source = [] {
    ImageSource s;
    const fs::path frame = fs::path(RSLAM_SOURCE_DIR) / ".." / "shared" / "data" / "irat" / "test_A_batch_000033.png";
    cv::Mat img = fs::exists(frame) ? cv::imread(frame.string(), cv::IMREAD_COLOR) : cv::Mat();
    if (!img.empty()) {
      cv::resize(img, s.base, cv::Size(640, 480));
      s.real = true;
    } else {
      s.base.create(480, 640, CV_8UC3);
      for (int y = 0; y < 480; ++y)
        for (int x = 0; x < 640; ++x) s.base.at<cv::Vec3b>(y, x) = cv::Vec3b(x / 3, y / 2, (x + y) / 5);
    }
    return s;
  }();
  return source;
}

// Frame seq: the base image with noise of +-2 in a few pixels per row, like sensor noise.
std::vector<uint8_t> ImageCdr(uint64_t seq) {
  const cv::Mat& base = Source().base;
  msg::Image image;
  image.header = {"robot1", seq, static_cast<int64_t>(seq * 33'333'333)};
  image.width = 640;
  image.height = 480;
  image.encoding = "bgr8";
  image.step = 640 * 3;
  image.data.assign(base.data, base.data + base.total() * base.elemSize());
  uint32_t r = static_cast<uint32_t>(seq) * 2654435761u + 7;
  for (std::size_t i = 0; i < image.data.size(); i += 7) {
    r = r * 1664525u + 1013904223u;
    image.data[i] = static_cast<uint8_t>(image.data[i] + ((r >> 29) & 3) - 1);
  }
  return bus::ToCdr(image);
}

std::unique_ptr<bus::Participant> Make(int domain, const std::string& robot) {
  bus::BusConfig c;
  c.domain_id = domain;
  c.robot_id = robot;
  return bus::Participant::Create(c);
}

fs::path BenchDir() {
  const fs::path dir = fs::temp_directory_path() / "rslam_bench_record";
  fs::create_directories(dir);
  return dir;
}

// Images published on the bus (reliable keep-all writer: lossless back-pressure), recorded by an
// in-process Recorder into a zstd MCAP file. Throughput = image bytes in the file per second.
void BM_RecordImagesThroughBus(benchmark::State& state) {
  const std::string compression = state.range(0) == 0 ? "zstd" : state.range(0) == 1 ? "lz4" : "none";
  testing::TestDomain domain;
  auto recorder_pp = Make(domain.id(), "rslam-record");
  auto robot_pp = Make(domain.id(), "robot1");
  RecorderOptions o;
  o.file.path = (BenchDir() / ("images_" + compression + ".mcap")).string();
  o.file.compression = compression;
  o.topics_regex = "^camera/image$";
  Recorder recorder(*recorder_pp, o);
  auto writer = robot_pp->CreateRawWriter(bus::TopicSpec{"camera/image", "rslam::msg::Image",
                                                         bus::KeyReaderFor<msg::Image>(), bus::QosPreset::kStream, "robot1"});
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((writer->MatchedReaders() < 1 || recorder.Subscriptions()[0].matched_writers < 1) &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(5ms);
  std::vector<std::vector<uint8_t>> frames;
  for (uint64_t i = 0; i < 16; ++i) frames.push_back(ImageCdr(i));  // prepared outside the timing
  constexpr int kBatch = 120;  // 4 s of 30 Hz video
  uint64_t sent = 0;
  const std::clock_t cpu_start = std::clock();  // every thread of the process: bus, recorder, publisher
  for (auto _ : state) {
    for (int i = 0; i < kBatch; ++i) writer->Write(frames[sent++ % frames.size()]);
    while (recorder.Stats().written < sent) std::this_thread::sleep_for(100us);  // until it is in the file
  }
  recorder.Stop();
  const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  const RecorderStats st = recorder.Stats();
  if (st.dropped > 0 || st.written != sent) state.SkipWithError("messages dropped");
  const double raw = static_cast<double>(sent) * frames[0].size();
  // Throughput per CPU-second of the whole process (publisher included): what one core sustains
  // when the machine is not shared.
  state.counters["MB_per_cpu_s"] = raw / 1e6 / cpu_s;
  state.SetBytesProcessed(static_cast<int64_t>(raw));
  state.SetItemsProcessed(static_cast<int64_t>(sent));
  state.counters["dropped"] = static_cast<double>(st.dropped);
  state.counters["file_ratio"] = static_cast<double>(fs::file_size(recorder.paths()[0])) / raw;
  state.SetLabel(compression + ", 640x480 bgr8, " + (Source().real ? "iRat frame" : "synthetic"));
  fs::remove(recorder.paths()[0]);
}

// The storage side alone: RecordingWriter (copy into the chunk, compress, write) per image.
// range(0): 0 zstd, 1 lz4, 2 none; range(1): zstd level.
void BM_WriteImages(benchmark::State& state) {
  const std::string compression = state.range(0) == 0 ? "zstd" : state.range(0) == 1 ? "lz4" : "none";
  RecordingFileOptions o;
  o.path = (BenchDir() / ("write_" + compression + ".mcap")).string();
  o.compression = compression;
  o.compression_level = static_cast<int>(state.range(1));
  RecordingWriter w(o, "cyclone");
  std::vector<std::vector<uint8_t>> frames;
  for (uint64_t i = 0; i < 16; ++i) frames.push_back(ImageCdr(i));
  const RecordedTopic& topic = TopicTable()[0];
  uint64_t n = 0;
  const std::clock_t cpu_start = std::clock();
  for (auto _ : state) {
    w.Write(topic, "robot1", n, n, frames[n % frames.size()]);
    ++n;
  }
  w.Close();
  state.counters["MB_per_cpu_s"] =
      n * frames[0].size() / 1e6 / (static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
  state.SetBytesProcessed(static_cast<int64_t>(n * frames[0].size()));
  state.SetItemsProcessed(static_cast<int64_t>(n));
  state.counters["file_ratio"] = static_cast<double>(fs::file_size(o.path)) / (n * frames[0].size());
  state.SetLabel(compression + (compression == "zstd" ? " level " + std::to_string(o.compression_level) : "") +
                 ", 640x480 bgr8");
  fs::remove(o.path);
}

// `rslam play --max` into one subscriber: range(0) = 0: 5000 Velocity messages (stream QoS),
// 1: 300 images (sensor QoS, acknowledged one by one).
void BM_PlayMax(benchmark::State& state) {
  const bool images = state.range(0) == 1;
  const int count = images ? 300 : 5000;
  const fs::path path = BenchDir() / (images ? "play_images.mcap" : "play_velocity.mcap");
  {
    RecordingFileOptions o;
    o.path = path.string();
    RecordingWriter w(o, "cyclone");
    for (int i = 0; i < count; ++i) {
      const uint64_t t = 1'000'000'000ull + i * 1'000'000ull;
      if (images) {
        w.Write(TopicTable()[0], "robot1", t, t, ImageCdr(i));
      } else {
        msg::Velocity v;
        FillExample(v, i);
        v.header.robot_id = "robot1";
        w.Write(TopicTable()[1], "robot1", t, t, bus::ToCdr(v));
      }
    }
  }
  testing::TestDomain domain;
  auto player_pp = Make(domain.id(), "rslam-play");
  auto reader_pp = Make(domain.id(), "tester");
  const RecordedTopic& topic = TopicTable()[images ? 0 : 1];
  auto reader = reader_pp->CreateRawReader(
      bus::TopicSpec{topic.name, topic.type->type_name, topic.type->key_reader, topic.qos, "robot1"});
  std::atomic<uint64_t> received{0};
  std::atomic<bool> stop{false};
  std::thread taker([&] {
    std::vector<bus::RawSample> batch;
    while (!stop) {
      reader->Wait(50ms);
      batch.clear();
      received += reader->Take(batch, 256);
    }
  });
  PlayOptions options;
  options.max_speed = true;
  options.settle = 0ms;  // same process: both sides match at once
  uint64_t expected = 0;
  for (auto _ : state) {
    const PlayReport report = PlayFile(*player_pp, path.string(), options);
    expected += report.messages;
    while (received < expected) std::this_thread::sleep_for(50us);
  }
  stop = true;
  reader->Interrupt();
  taker.join();
  state.SetItemsProcessed(static_cast<int64_t>(expected));
  state.SetLabel(images ? "640x480 bgr8 images, sensor QoS" : "Velocity, stream QoS");
  fs::remove(path);
}

BENCHMARK(BM_RecordImagesThroughBus)->DenseRange(0, 2)->Iterations(2)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WriteImages)->Args({0, 1})->Args({0, -3})->Args({1, 1})->Args({2, 1})->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PlayMax)->DenseRange(0, 1)->Iterations(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rslam::record
