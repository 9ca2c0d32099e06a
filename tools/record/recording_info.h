#pragma once
// What `rslam info` tells about a recording: topics, types, robots, message counts, duration,
// size and compression, from a fully validated McapReader (a damaged file is refused whole).

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rslam::record {

struct ChannelInfo {
  uint16_t id = 0;
  std::string topic;       // MCAP topic, "/robot1/camera/image"
  std::string dds_topic;   // from metadata ("" if absent)
  std::string type;        // schema name
  std::string robot;
  std::string qos;
  std::string dds_vendor;
  uint64_t message_count = 0;
};

struct RecordingInfo {
  std::string path;
  uint64_t size_bytes = 0;
  std::string profile;
  std::string library;
  std::vector<std::string> compressions;  // distinct chunk compressions ("none" for stored)
  uint64_t chunk_count = 0;
  uint64_t message_count = 0;
  uint64_t start_time_ns = 0;  // log time of the first message (0 if none)
  uint64_t end_time_ns = 0;
  std::vector<std::string> robots;  // sorted
  std::vector<ChannelInfo> channels;

  double duration_s() const { return message_count == 0 ? 0.0 : (end_time_ns - start_time_ns) * 1e-9; }
};

// Throws mcap::McapError for a damaged file, std::runtime_error if it cannot be opened.
RecordingInfo DescribeRecording(const std::string& path);

// {"path", "size_bytes", "profile", "library", "compression": [...], "chunk_count",
//  "message_count", "start_time_ns", "end_time_ns", "duration_s", "robots": [...],
//  "topics": [{"topic", "type", "message_count"}], "channels": [{"id", "topic", "dds_topic",
//  "type", "robot", "qos", "dds_vendor", "message_count"}]}
nlohmann::json ToJson(const RecordingInfo& info);
// A human-readable summary (rosbag2 `ros2 bag info` style).
std::string FormatRecordingInfo(const RecordingInfo& info);

}  // namespace rslam::record
