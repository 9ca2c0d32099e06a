#include "common/mcap/mcap_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "common/mcap/chunk_compression.h"
#include "common/mcap/mcap_crc32.h"

namespace rslam::mcap {

McapWriter::McapWriter() = default;

McapWriter::~McapWriter() {
  try {
    Close();
  } catch (...) {
    AbandonFile();
  }
}

void McapWriter::AbandonFile() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void McapWriter::Open(const std::string& path, const McapWriterOptions& options) {
  if (is_open()) throw std::logic_error("McapWriter::Open: " + path_ + " is still open");
  try {
    options.Validate();
  } catch (const ConfigError& e) {
    throw std::invalid_argument(std::string("McapWriterOptions: ") + e.what());
  }
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
  fd_ = fd;
  path_ = path;
  options_ = options;
  file_offset_ = 0;
  data_crc_ = 0;
  compressor_ = std::make_unique<ChunkCompressor>(options.compression, options.compression_level);
  schemas_.clear();
  channels_.clear();
  statistics_ = {};
  chunk_indexes_.clear();
  chunk_.clear();
  chunk_.reserve(static_cast<std::size_t>(options.chunk_size) + (1 << 20));
  chunk_has_messages_ = false;
  chunk_message_index_.assign(1, {});

  std::vector<std::byte> head;
  head.reserve(256);
  RecordBuilder b(head);
  b.Raw(kMagic.data(), kMagic.size());
  const auto r = b.BeginRecord(Opcode::kHeader);
  b.String(options.profile);
  b.String(kRslamMcapLibrary);
  b.EndRecord(r);
  WriteToFile(head, true);
}

uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding,
                               const std::string& data) {
  if (!is_open()) throw std::logic_error("McapWriter::AddSchema: no open file");
  if (schemas_.size() >= 0xFFFF) throw std::invalid_argument("McapWriter: too many schemas");
  Schema s{static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data};
  // Into the open chunk, so every chunk that survives a crash carries its definitions in order.
  RecordBuilder b(chunk_);
  AppendSchema(b, s);
  schemas_.push_back(std::move(s));
  ++statistics_.schema_count;
  return schemas_.back().id;
}

uint16_t McapWriter::AddChannel(uint16_t schema_id, const std::string& topic,
                                const std::string& message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  if (!is_open()) throw std::logic_error("McapWriter::AddChannel: no open file");
  if (schema_id > schemas_.size()) {
    throw std::invalid_argument("McapWriter::AddChannel(" + topic + "): unknown schema id " +
                                std::to_string(schema_id));
  }
  if (channels_.size() >= 0xFFFE) throw std::invalid_argument("McapWriter: too many channels");
  Channel c{static_cast<uint16_t>(channels_.size() + 1), schema_id, topic, message_encoding,
            metadata};
  RecordBuilder b(chunk_);
  AppendChannel(b, c);
  channels_.push_back(std::move(c));
  chunk_message_index_.resize(channels_.size() + 1);
  ++statistics_.channel_count;
  return channels_.back().id;
}

void McapWriter::Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns,
                       uint64_t publish_time_ns, std::span<const std::byte> data) {
  if (!is_open()) throw std::logic_error("McapWriter::Write: no open file");
  if (channel_id == 0 || channel_id > channels_.size()) {
    throw std::invalid_argument("McapWriter::Write: unknown channel id " +
                                std::to_string(channel_id));
  }
  const uint64_t offset = chunk_.size();
  // Message record header built on the stack, then the payload: the only copy of the data.
  std::byte head[kRecordPrefixSize + kMessageHeaderSize];
  head[0] = static_cast<std::byte>(Opcode::kMessage);
  const uint64_t len = kMessageHeaderSize + data.size();
  std::memcpy(head + 1, &len, 8);
  std::memcpy(head + 9, &channel_id, 2);
  std::memcpy(head + 11, &sequence, 4);
  std::memcpy(head + 15, &log_time_ns, 8);
  std::memcpy(head + 23, &publish_time_ns, 8);
  chunk_.insert(chunk_.end(), head, head + sizeof(head));
  chunk_.insert(chunk_.end(), data.begin(), data.end());

  chunk_message_index_[channel_id].emplace_back(log_time_ns, offset);
  if (!chunk_has_messages_) {
    chunk_start_time_ = chunk_end_time_ = log_time_ns;
    chunk_has_messages_ = true;
  } else {
    chunk_start_time_ = std::min(chunk_start_time_, log_time_ns);
    chunk_end_time_ = std::max(chunk_end_time_, log_time_ns);
  }
  if (statistics_.message_count == 0) {
    statistics_.message_start_time = statistics_.message_end_time = log_time_ns;
  } else {
    statistics_.message_start_time = std::min(statistics_.message_start_time, log_time_ns);
    statistics_.message_end_time = std::max(statistics_.message_end_time, log_time_ns);
  }
  ++statistics_.message_count;
  ++statistics_.channel_message_counts[channel_id];

  if (chunk_.size() >= static_cast<uint64_t>(options_.chunk_size)) FlushChunk();
}

void McapWriter::Flush() {
  if (!is_open()) throw std::logic_error("McapWriter::Flush: no open file");
  FlushChunk();
}

void McapWriter::FlushChunk() {
  if (chunk_.empty()) return;
  const uint32_t crc = Crc32(chunk_.data(), chunk_.size());
  std::span<const std::byte> records = chunk_;
  if (!options_.compression.empty()) {
    compressor_->Compress(chunk_, compressed_);
    records = compressed_;
  }

  ChunkIndex ci;
  ci.message_start_time = chunk_has_messages_ ? chunk_start_time_ : 0;
  ci.message_end_time = chunk_has_messages_ ? chunk_end_time_ : 0;
  ci.chunk_start_offset = file_offset_;
  ci.compression = options_.compression;
  ci.compressed_size = records.size();
  ci.uncompressed_size = chunk_.size();

  scratch_.clear();
  RecordBuilder b(scratch_);
  const auto r = b.BeginRecord(Opcode::kChunk);
  b.U64(ci.message_start_time);
  b.U64(ci.message_end_time);
  b.U64(ci.uncompressed_size);
  b.U32(crc);
  b.String(ci.compression);
  b.U64(records.size());
  const uint64_t content_len = scratch_.size() - r - 8 + records.size();
  std::memcpy(scratch_.data() + r, &content_len, 8);
  const std::size_t chunk_head_size = scratch_.size();
  ci.chunk_length = chunk_head_size + records.size();

  // Message Index records follow the chunk; built after the chunk header in the same buffer.
  for (uint16_t id = 1; id < chunk_message_index_.size(); ++id) {
    auto& entries = chunk_message_index_[id];
    if (entries.empty()) continue;
    ci.message_index_offsets[id] =
        ci.chunk_start_offset + ci.chunk_length + (scratch_.size() - chunk_head_size);
    const auto mr = b.BeginRecord(Opcode::kMessageIndex);
    b.U16(id);
    b.U32(static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [t, off] : entries) {
      b.U64(t);
      b.U64(off);
    }
    b.EndRecord(mr);
    entries.clear();
  }
  ci.message_index_length = scratch_.size() - chunk_head_size;

  WriteToFile(std::span<const std::byte>(scratch_).first(chunk_head_size), true);
  WriteToFile(records, true);
  WriteToFile(std::span<const std::byte>(scratch_).subspan(chunk_head_size), true);

  chunk_indexes_.push_back(std::move(ci));
  ++statistics_.chunk_count;
  chunk_.clear();
  chunk_has_messages_ = false;
}

void McapWriter::WriteToFile(std::span<const std::byte> bytes, bool in_data_section) {
  if (in_data_section && options_.data_section_crc) {
    data_crc_ = Crc32(bytes.data(), bytes.size(), data_crc_);
  }
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
    }
    done += static_cast<std::size_t>(n);
  }
  file_offset_ += bytes.size();
}

void McapWriter::Close() {
  if (!is_open()) return;
  FlushChunk();

  std::vector<std::byte> out;
  out.reserve(4096 + chunk_indexes_.size() * 128);
  RecordBuilder b(out);
  const auto de = b.BeginRecord(Opcode::kDataEnd);
  b.U32(options_.data_section_crc ? data_crc_ : 0);
  b.EndRecord(de);
  WriteToFile(out, true);
  out.clear();

  const uint64_t summary_start = file_offset_;
  struct Group {
    Opcode op;
    uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](Opcode op, auto&& append_all) {
    const std::size_t before = out.size();
    append_all();
    if (out.size() > before) groups.push_back({op, summary_start + before, out.size() - before});
  };
  group(Opcode::kSchema, [&] {
    for (const auto& s : schemas_) AppendSchema(b, s);
  });
  group(Opcode::kChannel, [&] {
    for (const auto& c : channels_) AppendChannel(b, c);
  });
  group(Opcode::kStatistics, [&] { AppendStatistics(b, statistics_); });
  group(Opcode::kChunkIndex, [&] {
    for (const auto& ci : chunk_indexes_) AppendChunkIndex(b, ci);
  });
  const uint64_t summary_offset_start = summary_start + out.size();
  for (const auto& g : groups) {
    const auto r = b.BeginRecord(Opcode::kSummaryOffset);
    b.U8(static_cast<uint8_t>(g.op));
    b.U64(g.start);
    b.U64(g.length);
    b.EndRecord(r);
  }
  // Length written directly: the summary CRC covers it (and everything up to summary_crc).
  b.U8(static_cast<uint8_t>(Opcode::kFooter));
  b.U64(kFooterContentSize);
  b.U64(summary_start);
  b.U64(summary_offset_start);
  b.U32(Crc32(out.data(), out.size()));
  b.Raw(kMagic.data(), kMagic.size());
  WriteToFile(out, false);

  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) throw std::runtime_error(path_ + ": close failed: " + std::strerror(errno));
}

}  // namespace rslam::mcap
