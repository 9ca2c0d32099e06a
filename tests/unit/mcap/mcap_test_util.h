#pragma once
// Shared by the MCAP tests: a scratch directory per test and a deterministic message stream.

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "common/mcap/mcap_reader.h"
#include "common/mcap/mcap_writer.h"
#include "tests/support/child_process.h"

namespace rslam::mcap::testing {

using ::rslam::testing::ScratchFolderForTest;

struct WrittenMessage {
  uint16_t channel;
  uint32_t sequence;
  uint64_t log_time;
  uint64_t publish_time;
  std::vector<std::byte> data;
};

inline const char* kPingIdl =
    "module rslam { module msg { @final struct Ping { uint32 seq; string text; "
    "sequence<uint8> data; }; }; };\n";

// Payload i: XCDR1 little-endian encapsulation header, then bytes that compress somewhat.
inline std::vector<std::byte> Payload(uint32_t i, std::size_t size) {
  std::vector<std::byte> d(size + 4);
  d[0] = std::byte{0x00};
  d[1] = std::byte{0x01};
  uint32_t x = i * 2654435761u + 12345;
  for (std::size_t k = 4; k < d.size(); ++k) {
    x = x * 1103515245u + 12345u;
    d[k] = static_cast<std::byte>((k % 7 == 0) ? (x >> 16) : (k / 64 + i));
  }
  return d;
}

// Declares 2 schemas and 3 channels (ids 1..3) with rslam metadata; returns the channel ids.
template <class Writer>
std::vector<uint16_t> DeclareChannels(Writer& w) {
  const uint16_t ping = w.AddSchema("rslam::msg::Ping", "omgidl", kPingIdl);
  const uint16_t image = w.AddSchema(
      "rslam::msg::Image", "omgidl",
      "module rslam { module msg { struct Image { uint32 width; uint32 height; "
      "sequence<uint8> pixels; }; }; };\n");
  std::vector<uint16_t> ids;
  ids.push_back(w.AddChannel(ping, "/robot1/ping", "cdr",
                             {{"robot", "robot1"}, {"qos", "reliable"},
                              {"dds_vendor", "cyclonedds"}, {"dds_topic", "rt/robot1/ping"}}));
  ids.push_back(w.AddChannel(image, "/robot1/camera/image", "cdr",
                             {{"robot", "robot1"}, {"qos", "sensor"},
                              {"dds_vendor", "cyclonedds"},
                              {"dds_topic", "rt/robot1/camera/image"}}));
  ids.push_back(w.AddChannel(ping, "/robot2/ping", "cdr",
                             {{"robot", "robot2"}, {"qos", "reliable"},
                              {"dds_vendor", "fastdds"}, {"dds_topic", "rt/robot2/ping"}}));
  return ids;
}

// n messages over the 3 channels; channel 2's log times lag so files are not time-sorted.
inline std::vector<WrittenMessage> MakeMessages(int n) {
  std::vector<WrittenMessage> out;
  for (int i = 0; i < n; ++i) {
    const uint16_t ch = static_cast<uint16_t>(1 + i % 3);
    const uint64_t t = 1'000'000'000ull + uint64_t(i) * 1'000'000ull - (ch == 2 ? 2'500'000ull : 0);
    const std::size_t size = ch == 2 ? 3000 + (i * 37) % 2000 : (i * 13) % 200;
    out.push_back({ch, static_cast<uint32_t>(i), t, t + 17, Payload(i, size)});
  }
  return out;
}

template <class Writer>
void WriteAll(Writer& w, const std::vector<WrittenMessage>& msgs) {
  for (const auto& m : msgs) w.Write(m.channel, m.sequence, m.log_time, m.publish_time, m.data);
}

// Expected read order: by log time, ties in write order.
inline std::vector<WrittenMessage> InLogTimeOrder(std::vector<WrittenMessage> msgs) {
  std::stable_sort(msgs.begin(), msgs.end(),
                   [](const auto& a, const auto& b) { return a.log_time < b.log_time; });
  return msgs;
}

inline std::vector<WrittenMessage> ReadAll(const McapReader& r, const MessageFilter& f = {}) {
  std::vector<WrittenMessage> out;
  r.ForEachMessage(f, [&](const MessageView& v) {
    out.push_back({v.channel->id, v.sequence, v.log_time, v.publish_time,
                   std::vector<std::byte>(v.data.begin(), v.data.end())});
  });
  return out;
}

inline std::vector<std::byte> ReadFile(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<char> c((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(c.size());
  std::memcpy(out.data(), c.data(), c.size());
  return out;
}

inline void WriteFile(const std::filesystem::path& p, std::span<const std::byte> bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace rslam::mcap::testing
