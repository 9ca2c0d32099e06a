#pragma once
// The storage side of `rslam record`: serialized messages into MCAP, one channel per
// (topic, robot), created on the first message. Knows nothing of DDS beyond the names it stores.
//
// Channel layout (read back by the player and `rslam info`):
//   topic            "/<robot>/<dds topic>", e.g. "/robot1/camera/image"
//   message encoding "cdr" (the bytes as they crossed the wire, encapsulation header included)
//   schema           name = type name ("rslam::msg::Image"), encoding "omgidl", data = IDL text
//   metadata         robot, qos (preset name), dds_vendor, dds_topic
//   sequence         0, 1, 2, ... per channel
//   log_time         receive time (ns since the Unix epoch); publish_time: DDS source timestamp

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/mcap/mcap_split_writer.h"
#include "common/mcap/mcap_writer.h"
#include "tools/record/recorded_topic.h"

namespace rslam::record {

struct RecordingFileOptions {
  std::string path;                  // the file; with splitting, the base of <base>_0000.mcap ...
  std::string compression = "zstd";  // "zstd", "lz4" or "none"
  int compression_level = 1;         // zstd level: 1 fast; negative levels are faster still
  uint64_t split_bytes = 0;          // 0 = no size split
  uint64_t split_duration_ns = 0;    // 0 = no duration split
  int64_t chunk_size = 4 << 20;

  bool splits() const { return split_bytes > 0 || split_duration_ns > 0; }
};

// "/robot1/camera/image" for ("camera/image", "robot1").
std::string ChannelTopic(const std::string& robot, const std::string& dds_topic);

class RecordingWriter {
 public:
  // Creates the (first) file. Throws std::invalid_argument for bad options, std::runtime_error
  // when the file cannot be created.
  RecordingWriter(const RecordingFileOptions& options, std::string dds_vendor);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // Appends one message of `robot` on `topic`, declaring its channel first if it is new.
  void Write(const RecordedTopic& topic, const std::string& robot, uint64_t log_time_ns,
             uint64_t publish_time_ns, std::span<const uint8_t> cdr);
  // Hands the open chunk to the OS (bounds what a kill can lose).
  void Flush();
  // Finishes the file(s). Idempotent.
  void Close();

  // Every file written so far.
  std::vector<std::string> paths() const;
  uint64_t message_count() const { return messages_; }
  std::size_t channel_count() const { return channels_.size(); }

 private:
  struct ChannelState {
    uint16_t id;
    uint32_t next_sequence = 0;
  };
  ChannelState& ChannelOf(const RecordedTopic& topic, const std::string& robot);

  const RecordingFileOptions options_;
  const std::string dds_vendor_;
  std::unique_ptr<mcap::McapWriter> single_;
  std::unique_ptr<mcap::McapSplitWriter> split_;
  std::map<std::string, uint16_t> schemas_;  // by type name
  std::map<std::pair<std::string, std::string>, ChannelState> channels_;  // by (topic, robot)
  uint64_t messages_ = 0;
};

}  // namespace rslam::record
