#include "common/mcap/mcap_split_writer.h"

#include <cstdio>
#include <stdexcept>

namespace rslam::mcap {
namespace {

std::string StripMcap(const std::string& p) {
  const std::string ext = ".mcap";
  if (p.size() > ext.size() && p.compare(p.size() - ext.size(), ext.size(), ext) == 0) {
    return p.substr(0, p.size() - ext.size());
  }
  return p;
}

}  // namespace

std::string McapSplitWriter::SplitPath(const std::string& base_path, int index) {
  char suffix[32];
  std::snprintf(suffix, sizeof(suffix), "_%04d.mcap", index);
  return StripMcap(base_path) + suffix;
}

McapSplitWriter::McapSplitWriter(const std::string& base_path, const McapWriterOptions& options,
                                 const McapSplitOptions& split)
    : base_(StripMcap(base_path)), options_(options), split_(split) {
  OpenNext();
}

void McapSplitWriter::OpenNext() {
  // Copy the definitions before Close/Open reset them.
  const std::vector<Schema> schemas = writer_.schemas();
  const std::vector<Channel> channels = writer_.channels();
  writer_.Close();
  const std::string path = SplitPath(base_, static_cast<int>(paths_.size()));
  writer_.Open(path, options_);
  paths_.push_back(path);
  for (const auto& s : schemas) writer_.AddSchema(s.name, s.encoding, s.data);
  for (const auto& c : channels) {
    writer_.AddChannel(c.schema_id, c.topic, c.message_encoding, c.metadata);
  }
}

uint16_t McapSplitWriter::AddSchema(const std::string& name, const std::string& encoding,
                                    const std::string& data) {
  return writer_.AddSchema(name, encoding, data);
}

uint16_t McapSplitWriter::AddChannel(uint16_t schema_id, const std::string& topic,
                                     const std::string& message_encoding,
                                     const std::map<std::string, std::string>& metadata) {
  return writer_.AddChannel(schema_id, topic, message_encoding, metadata);
}

void McapSplitWriter::Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns,
                            uint64_t publish_time_ns, std::span<const std::byte> data) {
  if (!writer_.is_open()) throw std::logic_error("McapSplitWriter::Write after Close");
  if (writer_.message_count() > 0) {
    const bool too_big =
        split_.max_file_bytes > 0 && writer_.approximate_size() >= split_.max_file_bytes;
    const bool too_long = split_.max_file_duration_ns > 0 && log_time_ns >= file_start_time_ &&
                          log_time_ns - file_start_time_ >= split_.max_file_duration_ns;
    if (too_big || too_long) OpenNext();
  }
  if (writer_.message_count() == 0) file_start_time_ = log_time_ns;
  writer_.Write(channel_id, sequence, log_time_ns, publish_time_ns, data);
}

void McapSplitWriter::Close() { writer_.Close(); }

}  // namespace rslam::mcap
