#pragma once
// A recording that rolls over to a new MCAP file after a size or log-time budget:
// <base>_0000.mcap, <base>_0001.mcap, ... Each file is complete on its own: it re-declares every
// schema and channel (with the same ids) before its first message.

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "common/mcap/mcap_writer.h"

namespace rslam::mcap {

struct McapSplitOptions {
  uint64_t max_file_bytes = 0;       // 0 = no size limit
  uint64_t max_file_duration_ns = 0;  // 0 = no log-time limit
};

class McapSplitWriter {
 public:
  // base_path: "dir/name" (a trailing ".mcap" is dropped). Opens <base>_0000.mcap.
  McapSplitWriter(const std::string& base_path, const McapWriterOptions& options,
                  const McapSplitOptions& split);
  McapSplitWriter(const McapSplitWriter&) = delete;
  McapSplitWriter& operator=(const McapSplitWriter&) = delete;

  uint16_t AddSchema(const std::string& name, const std::string& encoding,
                     const std::string& data);
  uint16_t AddChannel(uint16_t schema_id, const std::string& topic,
                      const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata);
  // Rolls over first when the current file already holds messages and is over budget.
  void Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns,
             uint64_t publish_time_ns, std::span<const std::byte> data);
  void Flush() { writer_.Flush(); }
  void Close();

  // Every file started so far, in order.
  const std::vector<std::string>& paths() const { return paths_; }
  static std::string SplitPath(const std::string& base_path, int index);

 private:
  void OpenNext();

  const std::string base_;
  const McapWriterOptions options_;
  const McapSplitOptions split_;
  McapWriter writer_;
  std::vector<std::string> paths_;
  uint64_t file_start_time_ = 0;
};

}  // namespace rslam::mcap
