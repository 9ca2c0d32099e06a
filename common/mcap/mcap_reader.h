#pragma once
// Reads an MCAP file (https://mcap.dev/spec) written by McapWriter or any conforming writer.
//
// Validation happens entirely in the constructor, before any data is yielded: magic at both
// ends, every record's opcode and length, every chunk decompressed and its uncompressed CRC
// checked, the data-section and summary CRCs when non-zero, message indexes, and the summary
// (schemas, channels, statistics, chunk indexes, summary offsets) cross-checked against the data
// section. Any violation throws McapError naming the byte offset and the problem; a file is
// refused whole, never half-read. A file without summary (summary_start = 0) is read from its
// data section alone. A file without closing magic/footer (a killed recorder) is refused with a
// hint to RecoverMcap (mcap_recovery.h).
//
// Cost: opening decompresses every chunk once; ForEachMessage decompresses the chunks it needs
// again (at most the chunks overlapping in log time are held at once).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "common/mcap/mcap_records.h"

namespace rslam::mcap {

struct McapReaderOptions {
  // Chunks claiming more uncompressed bytes than this are refused (bounds memory on bad input).
  uint64_t max_chunk_uncompressed_bytes = uint64_t{1} << 30;
  // Check chunk, data-section and summary CRCs (when non-zero). Off only for fuzzing the parser.
  bool verify_crcs = true;
};

struct MessageView {
  const Channel* channel = nullptr;
  uint32_t sequence = 0;
  uint64_t log_time = 0;
  uint64_t publish_time = 0;
  std::span<const std::byte> data;  // valid only during the callback
};

struct MessageFilter {
  std::set<std::string> topics;  // empty = every topic
  uint64_t start_time = 0;       // inclusive, log time ns
  uint64_t end_time = UINT64_MAX;  // inclusive
};

struct ChunkInfo {
  uint64_t offset = 0;  // of the Chunk record
  std::string compression;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  uint64_t message_count = 0;
};

class McapReader {
 public:
  // Maps and validates the file. Throws McapError (or std::runtime_error if it cannot be opened).
  explicit McapReader(const std::string& path, const McapReaderOptions& options = {});
  // Validates an in-memory file (takes ownership of the bytes).
  explicit McapReader(std::vector<std::byte> bytes, const McapReaderOptions& options = {});
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  const std::string& profile() const { return profile_; }
  const std::string& library() const { return library_; }
  const std::map<uint16_t, Schema>& schemas() const { return schemas_; }
  const std::map<uint16_t, Channel>& channels() const { return channels_; }
  // Counted from the data section (and equal to the summary's Statistics when there is one).
  const Statistics& statistics() const { return statistics_; }
  bool has_summary() const { return has_summary_; }
  const std::vector<ChunkInfo>& chunks() const { return chunk_infos_; }
  uint64_t file_size() const { return file_.size(); }

  // Calls visit for each message passing filter, in log-time order (ties in file order).
  void ForEachMessage(const MessageFilter& filter,
                      const std::function<void(const MessageView&)>& visit) const;

 private:
  struct MessageEntry {
    uint64_t log_time;
    uint64_t offset;  // in the uncompressed chunk, or in the file for messages outside chunks
    uint16_t channel;
  };
  struct ScannedChunk {
    ChunkInfo info;
    uint64_t record_length = 0;      // including opcode and length
    uint64_t records_offset = 0;     // file offset of the compressed records
    std::vector<MessageEntry> messages;
    std::map<uint16_t, uint64_t> message_index_offsets;
    uint64_t message_index_length = 0;
  };

  void Validate();
  uint64_t ScanDataSection(uint64_t end);
  void ScanChunk(uint64_t record_offset, std::span<const std::byte> content);
  void CheckMessageIndex(uint64_t record_offset, std::span<const std::byte> content);
  void ValidateSummary(uint64_t begin, uint64_t summary_start, uint64_t summary_offset_start,
                       uint64_t footer_offset);
  void AddSchema(const Schema& s, uint64_t offset);
  void AddChannel(const Channel& c, uint64_t offset);

  const McapReaderOptions options_;
  std::vector<std::byte> owned_;
  void* mapping_ = nullptr;
  std::span<const std::byte> file_;

  std::string profile_, library_;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, Channel> channels_;
  Statistics statistics_;
  bool has_summary_ = false;
  std::vector<ScannedChunk> chunks_;
  std::vector<ChunkInfo> chunk_infos_;
  std::vector<MessageEntry> loose_messages_;  // Message records outside chunks
};

}  // namespace rslam::mcap
