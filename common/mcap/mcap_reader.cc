#include "common/mcap/mcap_reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <unordered_map>

#include "common/mcap/chunk_compression.h"
#include "common/mcap/mcap_crc32.h"

namespace rslam::mcap {
namespace {

std::string At(uint64_t offset) { return "offset " + std::to_string(offset) + ": "; }

// Largest plausible expansion of a compressed chunk (zstd RLE blocks reach ~32768:1).
constexpr uint64_t kMaxCompressionRatio = 1 << 16;

struct RecordRef {
  uint8_t opcode;
  uint64_t offset;  // of the opcode byte
  std::span<const std::byte> content;
  uint64_t end() const { return offset + kRecordPrefixSize + content.size(); }
};

// Reads the record at offset, which must lie wholly before end.
RecordRef ReadRecord(std::span<const std::byte> bytes, uint64_t offset, uint64_t end,
                     std::string_view section) {
  if (end < offset || end - offset < kRecordPrefixSize) {
    throw McapError(At(offset) + std::string(section) + " ends inside a record header (" +
                    std::to_string(end - offset) + " bytes left)");
  }
  RecordRef r;
  r.opcode = static_cast<uint8_t>(bytes[offset]);
  uint64_t len;
  std::memcpy(&len, bytes.data() + offset + 1, 8);
  if (r.opcode == 0) throw McapError(At(offset) + "invalid opcode 0x00 in " + std::string(section));
  if (len > end - offset - kRecordPrefixSize) {
    throw McapError(At(offset) + OpcodeName(r.opcode) + " record length " + std::to_string(len) +
                    " runs past the end of the " + std::string(section) + " (" +
                    std::to_string(end - offset - kRecordPrefixSize) + " bytes left)");
  }
  r.offset = offset;
  r.content = bytes.subspan(offset + kRecordPrefixSize, len);
  return r;
}

}  // namespace

McapReader::McapReader(const std::string& path, const McapReaderOptions& options)
    : options_(options) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    ::close(fd);
    throw std::runtime_error(path + ": cannot stat: " + std::strerror(errno));
  }
  const std::size_t size = static_cast<std::size_t>(st.st_size);
  if (size > 0) {
    void* m = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (m == MAP_FAILED) {
      ::close(fd);
      throw std::runtime_error(path + ": cannot map: " + std::strerror(errno));
    }
    ::madvise(m, size, MADV_SEQUENTIAL);
    mapping_ = m;
    file_ = std::span<const std::byte>(static_cast<const std::byte*>(m), size);
  }
  ::close(fd);
  try {
    Validate();
  } catch (const McapError& e) {
    if (mapping_) ::munmap(mapping_, file_.size());
    mapping_ = nullptr;
    throw McapError(path + ": " + e.what());
  } catch (...) {
    if (mapping_) ::munmap(mapping_, file_.size());
    mapping_ = nullptr;
    throw;
  }
}

McapReader::McapReader(std::vector<std::byte> bytes, const McapReaderOptions& options)
    : options_(options), owned_(std::move(bytes)), file_(owned_) {
  Validate();
}

McapReader::~McapReader() {
  if (mapping_) ::munmap(mapping_, file_.size());
}

void McapReader::Validate() {
  const uint64_t size = file_.size();
  constexpr uint64_t kFooterRecordSize = kRecordPrefixSize + kFooterContentSize;
  if (size < kMagic.size() || std::memcmp(file_.data(), kMagic.data(), kMagic.size()) != 0) {
    throw McapError(At(0) + "not an MCAP file (wrong or missing magic)");
  }
  if (size < 2 * kMagic.size() + kFooterRecordSize + kRecordPrefixSize ||
      std::memcmp(file_.data() + size - kMagic.size(), kMagic.data(), kMagic.size()) != 0) {
    throw McapError(At(size) +
                    "no closing magic: the file is truncated or was never closed (recorder "
                    "killed?); RecoverMcap can rebuild it from its complete chunks");
  }
  const uint64_t footer_offset = size - kMagic.size() - kFooterRecordSize;
  if (static_cast<uint8_t>(file_[footer_offset]) != static_cast<uint8_t>(Opcode::kFooter)) {
    throw McapError(At(footer_offset) + "expected the Footer record before the closing magic");
  }
  RecordCursor footer(file_.subspan(footer_offset + 1, 8 + kFooterContentSize), footer_offset + 1,
                      "Footer");
  if (footer.U64() != kFooterContentSize) {
    throw McapError(At(footer_offset) + "Footer record length is not 20");
  }
  const uint64_t summary_start = footer.U64();
  const uint64_t summary_offset_start = footer.U64();
  const uint32_t summary_crc = footer.U32();

  const uint64_t data_end = ScanDataSection(footer_offset);
  has_summary_ = summary_start != 0;
  if (summary_crc != 0 && options_.verify_crcs) {
    const uint64_t crc_end = footer_offset + kRecordPrefixSize + 16;
    const uint32_t crc = Crc32(file_.data() + data_end, crc_end - data_end);
    if (crc != summary_crc) {
      throw McapError(At(footer_offset) + "summary CRC mismatch (footer says " +
                      std::to_string(summary_crc) + ", bytes give " + std::to_string(crc) + ")");
    }
  }
  ValidateSummary(data_end, summary_start, summary_offset_start, footer_offset);

  chunk_infos_.reserve(chunks_.size());
  for (const auto& c : chunks_) chunk_infos_.push_back(c.info);
}

void McapReader::AddSchema(const Schema& s, uint64_t offset) {
  if (s.id == 0) return;  // the spec says readers ignore schema id 0
  auto [it, inserted] = schemas_.emplace(s.id, s);
  if (!inserted && !(it->second == s)) {
    throw McapError(At(offset) + "Schema " + std::to_string(s.id) +
                    " redefined differently ('" + s.name + "' vs '" + it->second.name + "')");
  }
}

void McapReader::AddChannel(const Channel& c, uint64_t offset) {
  if (c.schema_id != 0 && !schemas_.count(c.schema_id)) {
    throw McapError(At(offset) + "Channel " + std::to_string(c.id) + " (" + c.topic +
                    ") refers to undefined schema " + std::to_string(c.schema_id));
  }
  auto [it, inserted] = channels_.emplace(c.id, c);
  if (!inserted && !(it->second == c)) {
    throw McapError(At(offset) + "Channel " + std::to_string(c.id) +
                    " redefined differently (topic '" + c.topic + "' vs '" + it->second.topic +
                    "')");
  }
}

uint64_t McapReader::ScanDataSection(uint64_t end) {
  uint64_t pos = kMagic.size();
  const RecordRef header = ReadRecord(file_, pos, end, "data section");
  if (header.opcode != static_cast<uint8_t>(Opcode::kHeader)) {
    throw McapError(At(pos) + "first record is " + OpcodeName(header.opcode) + ", not Header");
  }
  RecordCursor hc(header.content, pos + kRecordPrefixSize, "Header");
  profile_ = hc.String();
  library_ = hc.String();
  pos = header.end();

  bool previous_was_chunk_or_index = false;
  while (true) {
    const RecordRef r = ReadRecord(file_, pos, end, "data section");
    const uint64_t content_at = pos + kRecordPrefixSize;
    const auto op = static_cast<Opcode>(r.opcode);
    bool is_chunk_or_index = false;
    switch (op) {
      case Opcode::kSchema: {
        RecordCursor c(r.content, content_at, "Schema");
        AddSchema(ParseSchema(c), pos);
        break;
      }
      case Opcode::kChannel: {
        RecordCursor c(r.content, content_at, "Channel");
        AddChannel(ParseChannel(c), pos);
        break;
      }
      case Opcode::kMessage: {
        RecordCursor c(r.content, content_at, "Message");
        const uint16_t channel = c.U16();
        c.U32();
        const uint64_t log_time = c.U64();
        c.U64();
        if (!channels_.count(channel)) {
          throw McapError(At(pos) + "Message on undefined channel " + std::to_string(channel));
        }
        loose_messages_.push_back({log_time, pos, channel});
        break;
      }
      case Opcode::kChunk:
        ScanChunk(pos, r.content);
        is_chunk_or_index = true;
        break;
      case Opcode::kMessageIndex:
        if (!previous_was_chunk_or_index) {
          throw McapError(At(pos) + "MessageIndex record does not follow a Chunk");
        }
        CheckMessageIndex(pos, r.content);
        is_chunk_or_index = true;
        break;
      case Opcode::kAttachment:
        ++statistics_.attachment_count;
        break;
      case Opcode::kMetadata:
        ++statistics_.metadata_count;
        break;
      case Opcode::kDataEnd: {
        RecordCursor c(r.content, content_at, "DataEnd");
        const uint32_t crc = c.U32();
        if (crc != 0 && options_.verify_crcs) {
          const uint32_t actual = Crc32(file_.data(), pos);
          if (actual != crc) {
            throw McapError(At(pos) + "data section CRC mismatch (Data End says " +
                            std::to_string(crc) + ", bytes give " + std::to_string(actual) + ")");
          }
        }
        // Statistics as counted from the data section.
        statistics_.schema_count = static_cast<uint16_t>(schemas_.size());
        statistics_.channel_count = static_cast<uint32_t>(channels_.size());
        statistics_.chunk_count = static_cast<uint32_t>(chunks_.size());
        bool first = true;
        auto count = [&](const MessageEntry& m) {
          ++statistics_.message_count;
          ++statistics_.channel_message_counts[m.channel];
          if (first) {
            statistics_.message_start_time = statistics_.message_end_time = m.log_time;
            first = false;
          }
          statistics_.message_start_time = std::min(statistics_.message_start_time, m.log_time);
          statistics_.message_end_time = std::max(statistics_.message_end_time, m.log_time);
        };
        for (const auto& c : chunks_) std::for_each(c.messages.begin(), c.messages.end(), count);
        std::for_each(loose_messages_.begin(), loose_messages_.end(), count);
        return r.end();
      }
      case Opcode::kHeader:
      case Opcode::kFooter:
      case Opcode::kChunkIndex:
      case Opcode::kAttachmentIndex:
      case Opcode::kStatistics:
      case Opcode::kMetadataIndex:
      case Opcode::kSummaryOffset:
        throw McapError(At(pos) + OpcodeName(r.opcode) +
                        " record is not allowed in the data section (missing Data End?)");
      default:
        break;  // future or private record: skipped, as the spec asks
    }
    previous_was_chunk_or_index = is_chunk_or_index;
    pos = r.end();
  }
}

void McapReader::ScanChunk(uint64_t record_offset, std::span<const std::byte> content) {
  RecordCursor c(content, record_offset + kRecordPrefixSize, "Chunk");
  ScannedChunk chunk;
  chunk.info.offset = record_offset;
  chunk.record_length = kRecordPrefixSize + content.size();
  chunk.info.message_start_time = c.U64();
  chunk.info.message_end_time = c.U64();
  chunk.info.uncompressed_size = c.U64();
  const uint32_t crc = c.U32();
  chunk.info.compression = c.String();
  const uint64_t records_size = c.U64();
  chunk.records_offset = c.offset();
  const auto records = c.Bytes(records_size);
  chunk.info.compressed_size = records.size();
  const std::string where = At(record_offset) + "Chunk ";
  if (!IsSupportedCompression(chunk.info.compression)) {
    throw McapError(where + "uses unsupported compression '" + chunk.info.compression + "'");
  }
  const uint64_t limit =
      chunk.info.compression.empty()
          ? records.size()
          : std::min(options_.max_chunk_uncompressed_bytes,
                     records.size() * kMaxCompressionRatio + 4096);
  if (chunk.info.uncompressed_size > limit) {
    throw McapError(where + "claims " + std::to_string(chunk.info.uncompressed_size) +
                    " uncompressed bytes from " + std::to_string(records.size()) +
                    " compressed (limit " + std::to_string(limit) + ")");
  }
  std::vector<std::byte> plain;
  DecompressChunk(chunk.info.compression, records, chunk.info.uncompressed_size, record_offset,
                  plain);
  if (crc != 0 && options_.verify_crcs) {
    const uint32_t actual = Crc32(plain.data(), plain.size());
    if (actual != crc) {
      throw McapError(where + "uncompressed CRC mismatch (record says " + std::to_string(crc) +
                      ", records give " + std::to_string(actual) + ")");
    }
  }
  // Offsets inside the chunk are reported as "chunk at X + y".
  const std::string inner = "Chunk at " + std::to_string(record_offset) + ", inner ";
  uint64_t pos = 0;
  bool first = true;
  uint64_t tmin = 0, tmax = 0;
  while (pos < plain.size()) {
    RecordRef r;
    try {
      r = ReadRecord(plain, pos, plain.size(), "chunk records");
    } catch (const McapError& e) {
      throw McapError(where + "inner records malformed: " + e.what());
    }
    const uint64_t content_at = pos + kRecordPrefixSize;
    try {
      switch (static_cast<Opcode>(r.opcode)) {
        case Opcode::kSchema: {
          RecordCursor rc(r.content, content_at, "Schema");
          AddSchema(ParseSchema(rc), pos);
          break;
        }
        case Opcode::kChannel: {
          RecordCursor rc(r.content, content_at, "Channel");
          AddChannel(ParseChannel(rc), pos);
          break;
        }
        case Opcode::kMessage: {
          RecordCursor rc(r.content, content_at, "Message");
          const uint16_t channel = rc.U16();
          rc.U32();
          const uint64_t log_time = rc.U64();
          rc.U64();
          if (!channels_.count(channel)) {
            throw McapError(At(pos) + "Message on undefined channel " + std::to_string(channel));
          }
          chunk.messages.push_back({log_time, pos, channel});
          tmin = first ? log_time : std::min(tmin, log_time);
          tmax = first ? log_time : std::max(tmax, log_time);
          first = false;
          break;
        }
        case Opcode::kHeader:
        case Opcode::kFooter:
        case Opcode::kChunk:
        case Opcode::kMessageIndex:
        case Opcode::kChunkIndex:
        case Opcode::kAttachment:
        case Opcode::kAttachmentIndex:
        case Opcode::kStatistics:
        case Opcode::kMetadata:
        case Opcode::kMetadataIndex:
        case Opcode::kSummaryOffset:
        case Opcode::kDataEnd:
          throw McapError(At(pos) + OpcodeName(r.opcode) + " record is not allowed in a chunk");
        default:
          break;
      }
    } catch (const McapError& e) {
      throw McapError(inner + e.what());
    }
    pos = r.end();
  }
  if (!first && (tmin != chunk.info.message_start_time || tmax != chunk.info.message_end_time)) {
    throw McapError(where + "time range [" + std::to_string(chunk.info.message_start_time) + ", " +
                    std::to_string(chunk.info.message_end_time) +
                    "] does not match its messages [" + std::to_string(tmin) + ", " +
                    std::to_string(tmax) + "]");
  }
  chunk.info.message_count = chunk.messages.size();
  chunks_.push_back(std::move(chunk));
}

void McapReader::CheckMessageIndex(uint64_t record_offset, std::span<const std::byte> content) {
  ScannedChunk& chunk = chunks_.back();
  RecordCursor c(content, record_offset + kRecordPrefixSize, "MessageIndex");
  const uint16_t channel = c.U16();
  RecordCursor entries = c.Prefixed();
  if (chunk.message_index_offsets.count(channel)) {
    throw McapError(At(record_offset) + "second MessageIndex for channel " +
                    std::to_string(channel) + " after one chunk");
  }
  chunk.message_index_offsets[channel] = record_offset;
  chunk.message_index_length += kRecordPrefixSize + content.size();
  // Messages are in offset order within the chunk: binary search each indexed offset.
  uint64_t indexed = 0;
  while (!entries.AtEnd()) {
    const uint64_t at = entries.offset();
    const uint64_t log_time = entries.U64();
    const uint64_t offset = entries.U64();
    auto it = std::lower_bound(chunk.messages.begin(), chunk.messages.end(), offset,
                               [](const MessageEntry& m, uint64_t o) { return m.offset < o; });
    if (it == chunk.messages.end() || it->offset != offset || it->channel != channel ||
        it->log_time != log_time) {
      throw McapError(At(at) + "MessageIndex entry (time " + std::to_string(log_time) +
                      ", offset " + std::to_string(offset) + ") for channel " +
                      std::to_string(channel) + " points at no such message in the chunk");
    }
    ++indexed;
  }
  const auto n = static_cast<uint64_t>(
      std::count_if(chunk.messages.begin(), chunk.messages.end(),
                    [&](const MessageEntry& m) { return m.channel == channel; }));
  if (indexed != n) {
    throw McapError(At(record_offset) + "MessageIndex for channel " + std::to_string(channel) +
                    " lists " + std::to_string(indexed) + " messages, the chunk has " +
                    std::to_string(n));
  }
}

void McapReader::ValidateSummary(uint64_t begin, uint64_t summary_start,
                                 uint64_t summary_offset_start, uint64_t footer_offset) {
  const uint64_t offsets_begin = summary_offset_start != 0 ? summary_offset_start : footer_offset;
  const uint64_t expected_begin = summary_start != 0 ? summary_start : offsets_begin;
  if (expected_begin != begin || offsets_begin > footer_offset ||
      (summary_start != 0 && summary_start > offsets_begin)) {
    throw McapError(At(footer_offset) + "Footer offsets (summary_start " +
                    std::to_string(summary_start) + ", summary_offset_start " +
                    std::to_string(summary_offset_start) +
                    ") do not match the file layout (Data End ends at " + std::to_string(begin) +
                    ")");
  }
  std::unordered_map<uint64_t, const ScannedChunk*> chunk_at;
  for (const auto& c : chunks_) chunk_at[c.info.offset] = &c;
  std::set<uint64_t> indexed_chunks;
  bool have_statistics = false;
  std::map<uint64_t, uint8_t> summary_opcode_at;

  uint64_t pos = begin;
  while (pos < offsets_begin) {
    const RecordRef r = ReadRecord(file_, pos, offsets_begin, "summary section");
    const uint64_t content_at = pos + kRecordPrefixSize;
    summary_opcode_at[pos] = r.opcode;
    switch (static_cast<Opcode>(r.opcode)) {
      case Opcode::kSchema: {
        RecordCursor c(r.content, content_at, "Schema");
        const Schema s = ParseSchema(c);
        if (s.id == 0) break;
        auto it = schemas_.find(s.id);
        if (it == schemas_.end() || !(it->second == s)) {
          throw McapError(At(pos) + "summary Schema " + std::to_string(s.id) +
                          " does not match the data section");
        }
        break;
      }
      case Opcode::kChannel: {
        RecordCursor c(r.content, content_at, "Channel");
        const Channel ch = ParseChannel(c);
        auto it = channels_.find(ch.id);
        if (it == channels_.end() || !(it->second == ch)) {
          throw McapError(At(pos) + "summary Channel " + std::to_string(ch.id) + " (" + ch.topic +
                          ") does not match the data section");
        }
        break;
      }
      case Opcode::kStatistics: {
        if (have_statistics) throw McapError(At(pos) + "second Statistics record");
        have_statistics = true;
        RecordCursor c(r.content, content_at, "Statistics");
        Statistics s = ParseStatistics(c);
        const Statistics& d = statistics_;
        std::string bad;
        if (s.message_count != d.message_count) bad = "message_count";
        else if (s.chunk_count != d.chunk_count) bad = "chunk_count";
        else if (s.channel_count != d.channel_count) bad = "channel_count";
        else if (s.schema_count != d.schema_count) bad = "schema_count";
        else if (s.attachment_count != d.attachment_count) bad = "attachment_count";
        else if (s.metadata_count != d.metadata_count) bad = "metadata_count";
        else if (s.message_start_time != d.message_start_time) bad = "message_start_time";
        else if (s.message_end_time != d.message_end_time) bad = "message_end_time";
        else if (!s.channel_message_counts.empty() &&
                 s.channel_message_counts != d.channel_message_counts) {
          bad = "channel_message_counts";
        }
        if (!bad.empty()) {
          throw McapError(At(pos) + "Statistics " + bad + " does not match the data section");
        }
        break;
      }
      case Opcode::kChunkIndex: {
        RecordCursor c(r.content, content_at, "ChunkIndex");
        const ChunkIndex ci = ParseChunkIndex(c);
        auto it = chunk_at.find(ci.chunk_start_offset);
        if (it == chunk_at.end()) {
          throw McapError(At(pos) + "ChunkIndex points at offset " +
                          std::to_string(ci.chunk_start_offset) + ", where there is no Chunk");
        }
        const ScannedChunk& k = *it->second;
        if (ci.chunk_length != k.record_length || ci.compression != k.info.compression ||
            ci.compressed_size != k.info.compressed_size ||
            ci.uncompressed_size != k.info.uncompressed_size ||
            ci.message_start_time != k.info.message_start_time ||
            ci.message_end_time != k.info.message_end_time ||
            (!ci.message_index_offsets.empty() &&
             (ci.message_index_offsets != k.message_index_offsets ||
              ci.message_index_length != k.message_index_length))) {
          throw McapError(At(pos) + "ChunkIndex for the Chunk at " +
                          std::to_string(ci.chunk_start_offset) + " does not match that chunk");
        }
        if (!indexed_chunks.insert(ci.chunk_start_offset).second) {
          throw McapError(At(pos) + "second ChunkIndex for the Chunk at " +
                          std::to_string(ci.chunk_start_offset));
        }
        break;
      }
      case Opcode::kAttachmentIndex:
      case Opcode::kMetadataIndex:
        break;
      case Opcode::kHeader:
      case Opcode::kFooter:
      case Opcode::kMessage:
      case Opcode::kChunk:
      case Opcode::kMessageIndex:
      case Opcode::kAttachment:
      case Opcode::kMetadata:
      case Opcode::kDataEnd:
      case Opcode::kSummaryOffset:
        throw McapError(At(pos) + OpcodeName(r.opcode) +
                        " record is not allowed in the summary section");
      default:
        break;
    }
    pos = r.end();
  }
  if (!indexed_chunks.empty() && indexed_chunks.size() != chunks_.size()) {
    throw McapError(At(begin) + "summary indexes " + std::to_string(indexed_chunks.size()) +
                    " chunks, the data section has " + std::to_string(chunks_.size()));
  }
  while (pos < footer_offset) {
    const RecordRef r = ReadRecord(file_, pos, footer_offset, "summary offset section");
    if (r.opcode != static_cast<uint8_t>(Opcode::kSummaryOffset)) {
      throw McapError(At(pos) + OpcodeName(r.opcode) +
                      " record in the summary offset section (only SummaryOffset allowed)");
    }
    RecordCursor c(r.content, pos + kRecordPrefixSize, "SummaryOffset");
    const uint8_t group_opcode = c.U8();
    const uint64_t group_start = c.U64();
    const uint64_t group_length = c.U64();
    auto it = summary_opcode_at.find(group_start);
    if (it == summary_opcode_at.end() || it->second != group_opcode ||
        group_length > offsets_begin - group_start) {
      throw McapError(At(pos) + "SummaryOffset for " + OpcodeName(group_opcode) +
                      " points at no such group in the summary (start " +
                      std::to_string(group_start) + ", length " + std::to_string(group_length) +
                      ")");
    }
    pos = r.end();
  }
}

void McapReader::ForEachMessage(const MessageFilter& filter,
                                const std::function<void(const MessageView&)>& visit) const {
  std::set<uint16_t> wanted;
  for (const auto& [id, ch] : channels_) {
    if (filter.topics.empty() || filter.topics.count(ch.topic)) wanted.insert(id);
  }
  struct Pick {
    uint64_t log_time;
    uint32_t source;  // chunk index, or chunks_.size() for messages outside chunks
    uint64_t offset;
  };
  std::vector<Pick> picks;
  const auto source_count = static_cast<uint32_t>(chunks_.size());
  auto consider = [&](const MessageEntry& m, uint32_t source) {
    if (m.log_time >= filter.start_time && m.log_time <= filter.end_time &&
        wanted.count(m.channel)) {
      picks.push_back({m.log_time, source, m.offset});
    }
  };
  for (uint32_t i = 0; i < source_count; ++i) {
    const auto& c = chunks_[i];
    if (c.info.message_count == 0 || c.info.message_end_time < filter.start_time ||
        c.info.message_start_time > filter.end_time) {
      continue;
    }
    for (const auto& m : c.messages) consider(m, i);
  }
  for (const auto& m : loose_messages_) consider(m, source_count);
  // Stable: equal times keep file order (chunks are in file order, offsets ascend).
  std::stable_sort(picks.begin(), picks.end(),
                   [](const Pick& a, const Pick& b) { return a.log_time < b.log_time; });

  // A chunk stays decompressed from its first to its last pick only.
  std::vector<std::size_t> last_use(source_count, 0);
  for (std::size_t i = 0; i < picks.size(); ++i) {
    if (picks[i].source < source_count) last_use[picks[i].source] = i;
  }
  std::unordered_map<uint32_t, std::vector<std::byte>> open_chunks;
  for (std::size_t i = 0; i < picks.size(); ++i) {
    const Pick& p = picks[i];
    std::span<const std::byte> records;
    if (p.source == source_count) {
      records = file_;
    } else {
      auto it = open_chunks.find(p.source);
      if (it == open_chunks.end()) {
        const ScannedChunk& c = chunks_[p.source];
        it = open_chunks.emplace(p.source, std::vector<std::byte>{}).first;
        DecompressChunk(c.info.compression,
                        file_.subspan(c.records_offset, c.info.compressed_size),
                        c.info.uncompressed_size, c.info.offset, it->second);
      }
      records = it->second;
    }
    // Validated on open: the record is complete and its header fits.
    uint64_t len;
    std::memcpy(&len, records.data() + p.offset + 1, 8);
    const std::byte* content = records.data() + p.offset + kRecordPrefixSize;
    MessageView view;
    uint16_t channel;
    std::memcpy(&channel, content, 2);
    std::memcpy(&view.sequence, content + 2, 4);
    std::memcpy(&view.log_time, content + 6, 8);
    std::memcpy(&view.publish_time, content + 14, 8);
    view.channel = &channels_.at(channel);
    view.data = std::span<const std::byte>(content + kMessageHeaderSize, len - kMessageHeaderSize);
    visit(view);
    if (p.source < source_count && last_use[p.source] == i) open_chunks.erase(p.source);
  }
}

}  // namespace rslam::mcap
