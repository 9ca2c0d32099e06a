#include "tools/record/recording_writer.h"

#include <stdexcept>

namespace rslam::record {
namespace {

mcap::McapWriterOptions WriterOptions(const RecordingFileOptions& o) {
  if (o.compression != "zstd" && o.compression != "lz4" && o.compression != "none")
    throw std::invalid_argument("compression must be zstd, lz4 or none, got '" + o.compression + "'");
  mcap::McapWriterOptions w;
  w.profile = mcap::kProfileRslam;
  w.compression = o.compression == "none" ? "" : o.compression;
  w.chunk_size = o.chunk_size;
  w.compression_level = o.compression_level;
  w.Validate();
  return w;
}

}  // namespace

std::string ChannelTopic(const std::string& robot, const std::string& dds_topic) {
  return "/" + robot + "/" + dds_topic;
}

RecordingWriter::RecordingWriter(const RecordingFileOptions& options, std::string dds_vendor)
    : options_(options), dds_vendor_(std::move(dds_vendor)) {
  const mcap::McapWriterOptions w = WriterOptions(options);
  if (options.splits()) {
    split_ = std::make_unique<mcap::McapSplitWriter>(
        options.path, w, mcap::McapSplitOptions{options.split_bytes, options.split_duration_ns});
  } else {
    single_ = std::make_unique<mcap::McapWriter>();
    single_->Open(options.path, w);
  }
}

RecordingWriter::~RecordingWriter() {
  try {
    Close();
  } catch (...) {
    // Destructors must not throw; Close() reports errors to callers that want them.
  }
}

RecordingWriter::ChannelState& RecordingWriter::ChannelOf(const RecordedTopic& topic, const std::string& robot) {
  const auto key = std::make_pair(topic.name, robot);
  auto it = channels_.find(key);
  if (it != channels_.end()) return it->second;

  auto schema = schemas_.find(topic.type->type_name);
  if (schema == schemas_.end()) {
    const uint16_t id = single_ ? single_->AddSchema(topic.type->type_name, mcap::kSchemaEncodingOmgIdl, topic.type->idl)
                                : split_->AddSchema(topic.type->type_name, mcap::kSchemaEncodingOmgIdl, topic.type->idl);
    schema = schemas_.emplace(topic.type->type_name, id).first;
  }
  const std::map<std::string, std::string> metadata = {
      {mcap::kMetadataRobot, robot},
      {mcap::kMetadataQos, std::string(bus::PresetName(topic.qos))},
      {mcap::kMetadataDdsVendor, dds_vendor_},
      {mcap::kMetadataDdsTopic, topic.name},
  };
  const std::string channel_topic = ChannelTopic(robot, topic.name);
  const uint16_t id = single_ ? single_->AddChannel(schema->second, channel_topic, mcap::kMessageEncodingCdr, metadata)
                              : split_->AddChannel(schema->second, channel_topic, mcap::kMessageEncodingCdr, metadata);
  return channels_.emplace(key, ChannelState{id}).first->second;
}

void RecordingWriter::Write(const RecordedTopic& topic, const std::string& robot, uint64_t log_time_ns,
                            uint64_t publish_time_ns, std::span<const uint8_t> cdr) {
  ChannelState& channel = ChannelOf(topic, robot);
  const auto bytes = std::as_bytes(cdr);
  if (single_) {
    single_->Write(channel.id, channel.next_sequence, log_time_ns, publish_time_ns, bytes);
  } else {
    split_->Write(channel.id, channel.next_sequence, log_time_ns, publish_time_ns, bytes);
  }
  ++channel.next_sequence;
  ++messages_;
}

void RecordingWriter::Flush() {
  if (single_) single_->Flush();
  if (split_) split_->Flush();
}

void RecordingWriter::Close() {
  if (single_) single_->Close();
  if (split_) split_->Close();
}

std::vector<std::string> RecordingWriter::paths() const {
  if (single_) return {options_.path};
  return split_->paths();
}

}  // namespace rslam::record
