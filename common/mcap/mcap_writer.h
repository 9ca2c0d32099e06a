#pragma once
// Writes an MCAP file (https://mcap.dev/spec) of serialized DDS messages: Header, then Chunks of
// Schema/Channel/Message records each followed by its Message Index records, then Data End (with
// the data-section CRC), a summary section (Schemas, Channels, Statistics, Chunk Indexes), the
// Summary Offset section, Footer (with the summary CRC) and the closing magic.
//
// Durability: each chunk is handed to the OS (write(2)) as soon as it is complete, so a recorder
// killed with SIGKILL loses at most the open chunk; RecoverMcap (mcap_recovery.h) turns such a
// file back into a valid one. Messages are copied once, into the open chunk buffer, and each
// chunk is compressed once.

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/config/config_error.h"
#include "common/mcap/mcap_records.h"

namespace rslam::mcap {

inline constexpr const char* kRslamMcapLibrary = "rslam 0.1.0";

struct McapWriterOptions {
  std::string profile = "";      // "" or "rslam"
  std::string compression = "zstd";  // "zstd", "lz4" or "" (none)
  int compression_level = 1;     // zstd level (1 = fast); lz4 ignores positive levels
  int64_t chunk_size = 4 << 20;  // a chunk is closed once its uncompressed records reach this
  bool data_section_crc = true;  // CRC of the whole data section in Data End

  template <class V>
  void VisitFields(V& v) {
    v("profile", profile, "MCAP profile written in the header: empty or 'rslam'");
    v("compression", compression, "chunk compression: zstd, lz4 or empty for none");
    v("compression_level", compression_level, "zstd level (1..19; low is fast)");
    v("chunk_size", chunk_size, "target uncompressed chunk size in bytes");
    v("data_section_crc", data_section_crc, "write the CRC of the data section");
  }
  void Validate() const {
    Require(compression.empty() || compression == "zstd" || compression == "lz4", "compression",
            "must be zstd, lz4 or empty");
    Require(compression_level >= -5 && compression_level <= 22, "compression_level",
            "must be in -5..22");
    Require(chunk_size >= 1024 && chunk_size <= (int64_t{1} << 31), "chunk_size",
            "must be between 1 KiB and 2 GiB");
  }
};

class ChunkCompressor;

class McapWriter {
 public:
  McapWriter();
  // Closes an open file; errors at that point are swallowed (call Close() to see them).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // Creates (truncates) path and writes magic + Header. Throws std::invalid_argument for bad
  // options, std::runtime_error when the file cannot be created.
  void Open(const std::string& path, const McapWriterOptions& options = {});

  // Returns the new schema id (1, 2, ... in call order).
  uint16_t AddSchema(const std::string& name, const std::string& encoding,
                     const std::string& data);
  // Returns the new channel id (1, 2, ... in call order). schema_id 0 = no schema.
  uint16_t AddChannel(uint16_t schema_id, const std::string& topic,
                      const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata);

  // Appends one message (data = the serialized bytes, e.g. CDR with its encapsulation header).
  // Throws std::invalid_argument for an unknown channel.
  void Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns,
             uint64_t publish_time_ns, std::span<const std::byte> data);

  // Closes the open chunk now and hands it to the OS, so a crash cannot lose it. For recorders
  // of low-rate topics: call it periodically (e.g. every second) to bound what a kill loses.
  void Flush();

  // Flushes the open chunk and writes Data End, summary and footer. Idempotent.
  void Close();

  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  // Bytes in the file so far plus the uncompressed open chunk (for file splitting).
  uint64_t approximate_size() const { return file_offset_ + chunk_.size(); }
  uint64_t message_count() const { return statistics_.message_count; }
  const std::vector<Schema>& schemas() const { return schemas_; }
  const std::vector<Channel>& channels() const { return channels_; }

 private:
  void FlushChunk();
  void WriteToFile(std::span<const std::byte> bytes, bool in_data_section);
  void AbandonFile() noexcept;

  std::string path_;
  McapWriterOptions options_;
  int fd_ = -1;
  uint64_t file_offset_ = 0;
  uint32_t data_crc_ = 0;
  std::unique_ptr<ChunkCompressor> compressor_;

  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  Statistics statistics_;
  std::vector<ChunkIndex> chunk_indexes_;

  // The open chunk: uncompressed records, time range and per-channel (log_time, offset) index.
  std::vector<std::byte> chunk_;
  uint64_t chunk_start_time_ = 0;
  uint64_t chunk_end_time_ = 0;
  bool chunk_has_messages_ = false;
  std::vector<std::vector<std::pair<uint64_t, uint64_t>>> chunk_message_index_;  // by channel id

  std::vector<std::byte> compressed_;
  std::vector<std::byte> scratch_;
};

}  // namespace rslam::mcap
