#pragma once
// Shared by the record/play/info tests: the command-line binary as a child process (killed at
// the end of the test whatever happens), raw collectors on the bus, scratch folders, messages.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <fcntl.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <map>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/message_registry.h"
#include "common/bus/participant.h"
#include "common/bus/typed_cdr.h"
#include "rslam/msg/all_messages.h"
#include "tests/support/child_process.h"


namespace rslam::record::testing {

using namespace std::chrono_literals;
using rslam::testing::ChildProcess;
namespace fs = std::filesystem;

using rslam::testing::ScratchFolderForTest;


// build/bin/rslam once it has the record commands, else the test-only CLI.
inline std::string Cli() {
  static const std::string cli = [] {
    const std::string rslam = std::string(RSLAM_BINARY_DIR) + "/bin/rslam";
    if (fs::exists(rslam) && std::system(("'" + rslam + "' info --help > /dev/null 2>&1").c_str()) == 0) return rslam;
    return std::string(RSLAM_BINARY_DIR) + "/bin/rslam-record-testcli";
  }();
  return cli;
}

struct CliResult {
  int code = -1;
  std::string output;
};

// Runs the CLI to completion (at most timeout).
inline CliResult RunCli(const std::vector<std::string>& args, const fs::path& log,
                        std::chrono::milliseconds timeout = 60s) {
  ChildProcess p(Cli(), args, {.environment = {}, .log_file = log.string()});
  CliResult r;
  if (auto code = p.WaitExit(timeout)) r.code = *code;
  r.output = p.Output();
  return r;
}

// Collects the raw CDR of one topic in one partition on a thread of its own.
class RawCollector {
 public:
  RawCollector(bus::Participant& participant, const std::string& topic, const std::string& type_name,
               bus::QosPreset qos, const std::string& partition) {
    const auto* type = bus::FindMessageType(type_name);
    reader_ = participant.CreateRawReader(bus::TopicSpec{topic, type_name, type->key_reader, qos, partition});
    thread_ = std::thread([this] {
      std::vector<bus::RawSample> batch;
      while (!stop_) {
        reader_->Wait(100ms);
        batch.clear();
        reader_->Take(batch, 64);
        if (batch.empty()) continue;
        std::lock_guard lock(mutex_);
        for (auto& s : batch) messages_.push_back(std::move(s.cdr));
        cv_.notify_all();
      }
    });
  }
  ~RawCollector() {
    stop_ = true;
    reader_->Interrupt();
    thread_.join();
  }
  bool WaitForCount(std::size_t n, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    return cv_.wait_for(lock, timeout, [&] { return messages_.size() >= n; });
  }
  std::vector<std::vector<uint8_t>> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  int matched() const { return reader_->MatchedWriters(); }

 private:
  std::unique_ptr<bus::RawReader> reader_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<std::vector<uint8_t>> messages_;
};

inline std::unique_ptr<bus::Participant> MakeParticipant(int domain, const std::string& robot,
                                                         bus::Vendor vendor = bus::Vendor::kCyclone) {
  bus::BusConfig config;
  config.dds = bus::VendorName(vendor);
  config.domain_id = domain;
  config.robot_id = robot;
  return bus::Participant::Create(config);
}

// A 640x480 bgr8 (or smaller) image whose pixels depend on seq, compressible like a camera frame.
inline msg::Image MakeImage(const std::string& robot, uint64_t seq, uint32_t width = 640, uint32_t height = 480) {
  msg::Image image;
  image.header = {robot, seq, static_cast<int64_t>(1'700'000'000'000'000'000 + seq * 33'333'333)};
  image.width = width;
  image.height = height;
  image.encoding = "bgr8";
  image.step = width * 3;
  image.data.resize(std::size_t{image.step} * height);
  uint32_t noise = static_cast<uint32_t>(seq) * 2654435761u + 1;
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < image.step; ++x) {
      noise = noise * 1664525u + 1013904223u;
      image.data[std::size_t{y} * image.step + x] = static_cast<uint8_t>((x / 3 + y + seq * 7) / 4 + ((noise >> 28) & 3));
    }
  }
  return image;
}

// Waits until every writer matched at least n readers.
template <class Writers>
bool WaitForReaders(const Writers& writers, int n, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    bool all = true;
    for (const auto& w : writers) all = all && w->MatchedReaders() >= n;
    if (all) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(10ms);  // DDS offers no wait on matching
  }
}

}  // namespace rslam::record::testing

#include "common/mcap/mcap_reader.h"
#include "common/mcap/mcap_records.h"

namespace rslam::record::testing {

using ChannelKey = std::pair<std::string, std::string>;  // (dds topic, robot)

// Every message of the files per (dds topic, robot), in sequence order; fails the test when a
// channel's sequences are not 0, 1, 2, ... (across split files).
inline std::map<ChannelKey, std::vector<std::vector<uint8_t>>> ReadChannels(const std::vector<std::string>& paths) {
  std::map<ChannelKey, std::vector<std::pair<uint32_t, std::vector<uint8_t>>>> by_seq;
  for (const auto& path : paths) {
    const mcap::McapReader reader(path);
    reader.ForEachMessage({}, [&](const mcap::MessageView& m) {
      const ChannelKey key{m.channel->metadata.at(mcap::kMetadataDdsTopic), m.channel->metadata.at(mcap::kMetadataRobot)};
      const auto* p = reinterpret_cast<const uint8_t*>(m.data.data());
      by_seq[key].emplace_back(m.sequence, std::vector<uint8_t>(p, p + m.data.size()));
    });
  }
  std::map<ChannelKey, std::vector<std::vector<uint8_t>>> out;
  for (auto& [key, list] : by_seq) {
    std::stable_sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t i = 0; i < list.size(); ++i) {
      EXPECT_EQ(list[i].first, i) << key.first << "@" << key.second << ": sequence gap or repeat";
      out[key].push_back(std::move(list[i].second));
    }
  }
  return out;
}

}  // namespace rslam::record::testing

namespace rslam::record::testing {

// The bytes as they cross the wire: the bus pads serialized messages with zeros to a multiple
// of 4 (XCDR1 alignment) without noting the padding in the encapsulation options, so a reader
// (the recorder included) gets the padded size. Typed readers ignore the padding.
inline std::vector<uint8_t> Padded(std::vector<uint8_t> cdr) {
  cdr.resize((cdr.size() + 3) & ~std::size_t{3}, 0);
  return cdr;
}
inline std::vector<std::vector<uint8_t>> Padded(const std::vector<std::vector<uint8_t>>& all) {
  std::vector<std::vector<uint8_t>> out;
  for (const auto& m : all) out.push_back(Padded(m));
  return out;
}

}  // namespace rslam::record::testing
