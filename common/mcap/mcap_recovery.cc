#include "common/mcap/mcap_recovery.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <unordered_map>
#include <variant>

#include "common/mcap/chunk_compression.h"
#include "common/mcap/mcap_crc32.h"

namespace rslam::mcap {
namespace {

struct MappedFile {
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    ::fstat(fd, &st);
    size = static_cast<std::size_t>(st.st_size);
    if (size > 0) {
      void* m = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
      if (m == MAP_FAILED) {
        ::close(fd);
        throw std::runtime_error(path + ": cannot map: " + std::strerror(errno));
      }
      data = static_cast<const std::byte*>(m);
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (data) ::munmap(const_cast<std::byte*>(data), size);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::span<const std::byte> bytes() const { return {data, size}; }
  const std::byte* data = nullptr;
  std::size_t size = 0;
};

struct MessageRef {
  uint16_t channel;
  uint32_t sequence;
  uint64_t log_time, publish_time;
  std::span<const std::byte> data;
};
using Item = std::variant<Schema, Channel, MessageRef>;

// Complete record at pos within bytes, or nullopt.
std::optional<std::pair<uint8_t, std::span<const std::byte>>> CompleteRecord(
    std::span<const std::byte> bytes, uint64_t pos) {
  if (bytes.size() < pos || bytes.size() - pos < kRecordPrefixSize) return std::nullopt;
  const auto op = static_cast<uint8_t>(bytes[pos]);
  uint64_t len;
  std::memcpy(&len, bytes.data() + pos + 1, 8);
  if (op == 0 || len > bytes.size() - pos - kRecordPrefixSize) return std::nullopt;
  return std::make_pair(op, bytes.subspan(pos + kRecordPrefixSize, len));
}

// Parses Schema/Channel/Message records; throws McapError on malformed ones.
void ParseItems(std::span<const std::byte> records, std::vector<Item>& items) {
  uint64_t pos = 0;
  while (pos < records.size()) {
    const auto r = CompleteRecord(records, pos);
    if (!r) throw McapError("truncated record inside chunk");
    RecordCursor c(r->second, pos, "record");
    switch (static_cast<Opcode>(r->first)) {
      case Opcode::kSchema:
        items.emplace_back(ParseSchema(c));
        break;
      case Opcode::kChannel:
        items.emplace_back(ParseChannel(c));
        break;
      case Opcode::kMessage: {
        MessageRef m;
        m.channel = c.U16();
        m.sequence = c.U32();
        m.log_time = c.U64();
        m.publish_time = c.U64();
        m.data = c.Rest();
        items.emplace_back(m);
        break;
      }
      default:
        break;
    }
    pos += kRecordPrefixSize + r->second.size();
  }
}

}  // namespace

RecoveryReport RecoverMcap(const std::string& in_path, const std::string& out_path,
                           const McapWriterOptions& options, bool keep_input_compression,
                           uint64_t max_chunk_uncompressed_bytes) {
  if (in_path == out_path) throw std::invalid_argument("RecoverMcap: output must differ from input");
  const MappedFile in(in_path);
  const auto bytes = in.bytes();
  if (bytes.size() < kMagic.size() || std::memcmp(bytes.data(), kMagic.data(), kMagic.size()) != 0) {
    throw McapError(in_path + ": offset 0: not an MCAP file (wrong or missing magic)");
  }
  const auto header = CompleteRecord(bytes, kMagic.size());
  if (!header || header->first != static_cast<uint8_t>(Opcode::kHeader)) {
    throw McapError(in_path + ": offset 8: no complete Header record; nothing to recover");
  }
  RecordCursor hc(header->second, kMagic.size() + kRecordPrefixSize, "Header");
  McapWriterOptions out_options = options;
  out_options.profile = hc.String();

  // First pass over top-level records to find the input compression.
  uint64_t pos = kMagic.size() + kRecordPrefixSize + header->second.size();
  if (keep_input_compression) {
    for (uint64_t p = pos;;) {
      const auto r = CompleteRecord(bytes, p);
      if (!r) break;
      if (r->first == static_cast<uint8_t>(Opcode::kChunk)) {
        RecordCursor c(r->second, 0, "Chunk");
        try {
          c.Bytes(28);
          const std::string compression = c.String();
          if (IsSupportedCompression(compression)) out_options.compression = compression;
        } catch (const McapError&) {
        }
        break;
      }
      p += kRecordPrefixSize + r->second.size();
    }
  }

  McapWriter writer;
  writer.Open(out_path, out_options);
  RecoveryReport report;
  std::unordered_map<uint16_t, uint16_t> schema_ids, channel_ids;
  auto apply = [&](const std::vector<Item>& items) {
    for (const auto& item : items) {
      if (const auto* s = std::get_if<Schema>(&item)) {
        if (s->id != 0 && !schema_ids.count(s->id)) {
          schema_ids[s->id] = writer.AddSchema(s->name, s->encoding, s->data);
        }
      } else if (const auto* ch = std::get_if<Channel>(&item)) {
        if (channel_ids.count(ch->id)) continue;
        const auto sid = schema_ids.find(ch->schema_id);
        channel_ids[ch->id] = writer.AddChannel(sid == schema_ids.end() ? 0 : sid->second,
                                                ch->topic, ch->message_encoding, ch->metadata);
      } else {
        const auto& m = std::get<MessageRef>(item);
        const auto cid = channel_ids.find(m.channel);
        if (cid == channel_ids.end()) continue;  // its channel was lost: cannot be replayed
        writer.Write(cid->second, m.sequence, m.log_time, m.publish_time, m.data);
        ++report.messages;
      }
    }
  };

  bool saw_data_end = false;
  std::vector<std::byte> plain;
  std::vector<Item> items;
  while (true) {
    const auto r = CompleteRecord(bytes, pos);
    if (!r) break;
    const uint64_t next = pos + kRecordPrefixSize + r->second.size();
    items.clear();
    try {
      switch (static_cast<Opcode>(r->first)) {
        case Opcode::kSchema:
        case Opcode::kChannel:
        case Opcode::kMessage: {
          ParseItems(bytes.subspan(pos, next - pos), items);
          break;
        }
        case Opcode::kChunk: {
          RecordCursor c(r->second, pos + kRecordPrefixSize, "Chunk");
          c.U64();
          c.U64();
          const uint64_t uncompressed_size = c.U64();
          const uint32_t crc = c.U32();
          const std::string compression = c.String();
          const auto records = c.Bytes(c.U64());
          if (uncompressed_size > max_chunk_uncompressed_bytes ||
              (!compression.empty() && uncompressed_size > records.size() * (uint64_t{1} << 16))) {
            throw McapError("implausible chunk size");
          }
          DecompressChunk(compression, records, uncompressed_size, pos, plain);
          if (crc != 0 && Crc32(plain.data(), plain.size()) != crc) {
            throw McapError("chunk CRC mismatch");
          }
          ParseItems(plain, items);
          ++report.chunks;
          break;
        }
        case Opcode::kDataEnd:
          saw_data_end = true;
          break;
        default:
          break;
      }
    } catch (const McapError&) {
      break;  // a damaged record ends what can be trusted
    }
    if (saw_data_end) {
      pos = bytes.size();
      break;
    }
    apply(items);
    pos = next;
  }
  report.bytes_dropped = bytes.size() - pos;
  writer.Close();
  return report;
}

}  // namespace rslam::mcap
