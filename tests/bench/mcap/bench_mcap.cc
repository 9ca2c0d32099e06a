// MCAP recording and replay throughput with 640x480 RGB images as CDR payloads (4-byte header):
// synthetic frames (smoothed noise + gradients + sensor noise) and real iRat frames resized to
// 640x480. Rates are per CPU second of this process (one core; the machine is shared).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/mcap/mcap_crc32.h"
#include "common/mcap/mcap_reader.h"
#include "common/persistence/state_file.h"
#include "common/mcap/mcap_writer.h"

namespace rslam::mcap {
namespace {

constexpr int kWidth = 640, kHeight = 480;
constexpr int kFrames = 16;  // distinct frames cycled through

std::vector<std::vector<std::byte>> MakeFrames() {
  std::mt19937 rng(7);
  std::vector<std::vector<std::byte>> frames;
  for (int f = 0; f < kFrames; ++f) {
    std::vector<std::byte> d(4 + kWidth * kHeight * 3);
    d[1] = std::byte{0x01};  // XCDR1 little-endian
    // Coarse noise grid (bilinear upsampled) + horizontal/vertical gradients + pixel noise.
    constexpr int kGrid = 16;
    std::vector<float> grid((kWidth / kGrid + 2) * (kHeight / kGrid + 2) * 3);
    std::uniform_real_distribution<float> u(0, 120);
    for (auto& g : grid) g = u(rng);
    std::uniform_int_distribution<int> noise(-2, 2);  // sensor noise
    const int gw = kWidth / kGrid + 2;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const float fx = float(x) / kGrid, fy = float(y) / kGrid;
        const int ix = int(fx), iy = int(fy);
        const float ax = fx - ix, ay = fy - iy;
        for (int c = 0; c < 3; ++c) {
          auto g = [&](int gx, int gy) { return grid[(gy * gw + gx) * 3 + c]; };
          const float v = (1 - ay) * ((1 - ax) * g(ix, iy) + ax * g(ix + 1, iy)) +
                          ay * ((1 - ax) * g(ix, iy + 1) + ax * g(ix + 1, iy + 1));
          const int p = int(v + 0.1f * x * (c + 1) / 3 + 0.15f * y + f) + noise(rng);
          d[4 + (y * kWidth + x) * 3 + c] = static_cast<std::byte>(std::clamp(p, 0, 255));
        }
      }
    }
    frames.push_back(std::move(d));
  }
  return frames;
}

const std::vector<std::vector<std::byte>>& Frames() {
  static const auto frames = MakeFrames();
  return frames;
}

// Real camera frames (iRat arena, 416x240) resized to 640x480; empty if the data is absent.
std::vector<std::vector<std::byte>> LoadRealFrames() {
  std::vector<std::vector<std::byte>> frames;
  const char* env = std::getenv("RSLAM_SHARED_DATA");
  const std::filesystem::path dir =
      (env ? std::filesystem::path(env) : std::filesystem::path(RSLAM_SOURCE_DIR) / "../shared/data") /
      "irat";
  if (!std::filesystem::exists(dir)) return frames;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    cv::Mat img = cv::imread(e.path().string(), cv::IMREAD_COLOR);
    if (img.empty()) continue;
    cv::resize(img, img, cv::Size(kWidth, kHeight), 0, 0, cv::INTER_LINEAR);
    std::vector<std::byte> d(4 + img.total() * 3);
    d[1] = std::byte{0x01};
    std::memcpy(d.data() + 4, img.data, img.total() * 3);
    frames.push_back(std::move(d));
  }
  return frames;
}

std::string BenchPath(const char* name) {
  return (std::filesystem::temp_directory_path() /
          ("rslam_bench_mcap_" + std::to_string(::getpid()) + "_" + name + ".mcap"))
      .string();
}

// state.range(0): 0 = zstd level 1, 1 = lz4, 2 = none, 3 = zstd level 3.
McapWriterOptions OptionsFor(int64_t kind) {
  McapWriterOptions o;
  o.compression = kind == 1 ? "lz4" : kind == 2 ? "" : "zstd";
  o.compression_level = kind == 3 ? 3 : 1;
  return o;
}

void WriteImages(benchmark::State& state, const std::vector<std::vector<std::byte>>& frames) {
  if (frames.empty()) {
    state.SkipWithError("no frames (shared data absent)");
    return;
  }
  const std::string path = BenchPath("write");
  const McapWriterOptions options = OptionsFor(state.range(0));
  constexpr int kPerFile = 200;  // ~184 MB per file
  uint64_t bytes = 0, file_bytes = 0;
  for (auto _ : state) {
    McapWriter w;
    w.Open(path, options);
    const uint16_t s = w.AddSchema("rslam::msg::Image", "omgidl", "module rslam { ... };");
    const uint16_t ch = w.AddChannel(s, "/robot1/camera/image", "cdr", {{"robot", "robot1"}});
    for (int i = 0; i < kPerFile; ++i) {
      const auto& f = frames[i % frames.size()];
      w.Write(ch, i, 1'000'000'000ull + i * 33'000'000ull, 0, f);
      bytes += f.size();
    }
    w.Close();
    file_bytes += std::filesystem::file_size(path);
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
  state.counters["ratio"] = double(bytes) / double(file_bytes);
  state.counters["frames/s"] =
      benchmark::Counter(double(kPerFile) * state.iterations(), benchmark::Counter::kIsRate);
  std::filesystem::remove(path);
}
void BM_WriteImages(benchmark::State& state) { WriteImages(state, Frames()); }
BENCHMARK(BM_WriteImages)
    ->Arg(0)->Arg(1)->Arg(2)->Arg(3)
    ->ArgName("zstd1_lz4_none_zstd3")
    ->Unit(benchmark::kMillisecond);

void BM_WriteRealImages(benchmark::State& state) {
  static const auto frames = LoadRealFrames();
  WriteImages(state, frames);
}
BENCHMARK(BM_WriteRealImages)
    ->Arg(0)->Arg(1)->Arg(3)
    ->ArgName("zstd1_lz4_none_zstd3")
    ->Unit(benchmark::kMillisecond);

void BM_ReadImages(benchmark::State& state) {
  const auto& frames = Frames();
  const std::string path = BenchPath("read");
  constexpr int kCount = 200;
  {
    McapWriter w;
    w.Open(path, OptionsFor(state.range(0)));
    const uint16_t s = w.AddSchema("rslam::msg::Image", "omgidl", "module rslam { ... };");
    const uint16_t ch = w.AddChannel(s, "/robot1/camera/image", "cdr", {});
    for (int i = 0; i < kCount; ++i) w.Write(ch, i, i, i, frames[i % kFrames]);
    w.Close();
  }
  uint64_t bytes = 0, messages = 0;
  for (auto _ : state) {
    const McapReader r(path);  // validation (every chunk decompressed + CRC) included
    r.ForEachMessage({}, [&](const MessageView& v) {
      bytes += v.data.size();
      ++messages;
      benchmark::DoNotOptimize(v.data.data());
    });
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
  state.counters["messages/s"] = benchmark::Counter(double(messages), benchmark::Counter::kIsRate);
  std::filesystem::remove(path);
}
BENCHMARK(BM_ReadImages)
    ->Arg(0)->Arg(1)->Arg(2)
    ->ArgName("zstd1_lz4_none")
    ->Unit(benchmark::kMillisecond);

void BM_ReadSmallMessages(benchmark::State& state) {
  const std::string path = BenchPath("small");
  constexpr int kCount = 200'000;
  {
    McapWriter w;
    w.Open(path);
    const uint16_t ch = w.AddChannel(0, "/odom", "cdr", {});
    std::vector<std::byte> d(96, std::byte{1});
    for (int i = 0; i < kCount; ++i) w.Write(ch, i, i, i, d);
    w.Close();
  }
  uint64_t messages = 0, bytes = 0;
  for (auto _ : state) {
    const McapReader r(path);
    r.ForEachMessage({}, [&](const MessageView& v) {
      ++messages;
      bytes += v.data.size();
    });
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
  state.counters["messages/s"] = benchmark::Counter(double(messages), benchmark::Counter::kIsRate);
  std::filesystem::remove(path);
}
BENCHMARK(BM_ReadSmallMessages)->Unit(benchmark::kMillisecond);

// Why the MCAP library has its own CRC-32: slicing-by-8 vs the byte-wise rslam::Crc32.
void BM_Crc32(benchmark::State& state) {
  const auto& frame = Frames()[0];
  uint32_t crc = 0;
  for (auto _ : state) {
    crc = state.range(0) == 0 ? Crc32(frame.data(), frame.size())
                              : rslam::Crc32(frame.data(), frame.size());
    benchmark::DoNotOptimize(crc);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * frame.size()));
}
BENCHMARK(BM_Crc32)->Arg(0)->Arg(1)->ArgName("slicing8_bytewise");

}  // namespace
}  // namespace rslam::mcap
