#pragma once
// MCAP container format, major version 0 (https://mcap.dev/spec): magic, record opcodes and the
// little-endian primitives every record is built from. Records are <u8 opcode><u64 length>
// <content>; strings and byte arrays carry a u32 length prefix, maps and arrays a u32 byte
// length. Only what rslam writes and reads is modelled; unknown opcodes are skipped by readers.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rslam::mcap {

// Thrown for every malformed, truncated or inconsistent file; the message names the byte offset.
class McapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr std::array<uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
// Opcode (1) + content length (8).
inline constexpr std::size_t kRecordPrefixSize = 9;

enum class Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Names rslam's recorder and player agree on (schema/message encodings, channel metadata keys).
inline constexpr const char* kProfileRslam = "rslam";
inline constexpr const char* kSchemaEncodingOmgIdl = "omgidl";
inline constexpr const char* kMessageEncodingCdr = "cdr";
inline constexpr const char* kMetadataRobot = "robot";            // robot id
inline constexpr const char* kMetadataQos = "qos";                // QoS preset name
inline constexpr const char* kMetadataDdsVendor = "dds_vendor";   // e.g. "cyclonedds"
inline constexpr const char* kMetadataDdsTopic = "dds_topic";     // topic name on the wire

// Footer content: summary_start u64, summary_offset_start u64, summary_crc u32.
inline constexpr std::size_t kFooterContentSize = 20;
// Message content before the payload: channel u16, sequence u32, log_time u64, publish_time u64.
inline constexpr std::size_t kMessageHeaderSize = 22;

struct Schema {
  uint16_t id = 0;
  std::string name;      // fully qualified type name, e.g. "rslam::msg::Image"
  std::string encoding;  // "omgidl" for rslam
  std::string data;      // IDL text
  bool operator==(const Schema&) const = default;
};

struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  // "cdr" for rslam
  std::map<std::string, std::string> metadata;
  bool operator==(const Channel&) const = default;
};

struct Statistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0;
  uint32_t attachment_count = 0;
  uint32_t metadata_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
  bool operator==(const Statistics&) const = default;
};

struct ChunkIndex {
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  uint64_t chunk_start_offset = 0;
  uint64_t chunk_length = 0;
  std::map<uint16_t, uint64_t> message_index_offsets;
  uint64_t message_index_length = 0;
  std::string compression;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
};

// Appends little-endian MCAP primitives to a byte buffer.
class RecordBuilder {
 public:
  explicit RecordBuilder(std::vector<std::byte>& out) : out_(out) {}

  void U8(uint8_t v) { Raw(&v, 1); }
  void U16(uint16_t v) { Le(v); }
  void U32(uint32_t v) { Le(v); }
  void U64(uint64_t v) { Le(v); }
  void String(std::string_view s) {
    U32(static_cast<uint32_t>(s.size()));
    Raw(s.data(), s.size());
  }
  void Raw(const void* p, std::size_t n) {
    const std::size_t at = out_.size();
    out_.resize(at + n);
    if (n > 0) std::memcpy(out_.data() + at, p, n);
  }
  // Starts a record and returns the position of its length field, for EndRecord.
  std::size_t BeginRecord(Opcode op) {
    U8(static_cast<uint8_t>(op));
    const std::size_t at = out_.size();
    U64(0);
    return at;
  }
  void EndRecord(std::size_t length_at) {
    const uint64_t len = out_.size() - length_at - 8;
    std::memcpy(out_.data() + length_at, &len, 8);
  }
  // Starts a u32-byte-length-prefixed map or array; EndPrefixed fills in the length.
  std::size_t BeginPrefixed() {
    const std::size_t at = out_.size();
    U32(0);
    return at;
  }
  void EndPrefixed(std::size_t at) {
    const uint32_t len = static_cast<uint32_t>(out_.size() - at - 4);
    std::memcpy(out_.data() + at, &len, 4);
  }
  std::size_t size() const { return out_.size(); }

 private:
  template <class T>
  void Le(T v) {
    static_assert(std::endian::native == std::endian::little, "big-endian hosts not supported");
    Raw(&v, sizeof(T));
  }
  std::vector<std::byte>& out_;
};

// Bounds-checked little-endian cursor over one record's content. Every read past the end throws
// McapError naming base_offset (the file offset of the content) plus the position.
class RecordCursor {
 public:
  RecordCursor(std::span<const std::byte> content, uint64_t base_offset, std::string_view what)
      : data_(content), base_(base_offset), what_(what) {}

  uint8_t U8() { return Le<uint8_t>(); }
  uint16_t U16() { return Le<uint16_t>(); }
  uint32_t U32() { return Le<uint32_t>(); }
  uint64_t U64() { return Le<uint64_t>(); }
  std::string String() {
    const uint32_t n = U32();
    const auto b = Bytes(n);
    return std::string(reinterpret_cast<const char*>(b.data()), b.size());
  }
  std::span<const std::byte> Bytes(uint64_t n) {
    Need(n);
    auto s = data_.subspan(pos_, n);
    pos_ += n;
    return s;
  }
  // A u32-byte-length-prefixed map/array as a sub-cursor.
  RecordCursor Prefixed() {
    const uint32_t n = U32();
    const uint64_t at = base_ + pos_;
    return RecordCursor(Bytes(n), at, what_);
  }
  std::map<std::string, std::string> StringMap() {
    RecordCursor m = Prefixed();
    std::map<std::string, std::string> out;
    while (!m.AtEnd()) {
      std::string k = m.String();
      out[std::move(k)] = m.String();
    }
    return out;
  }
  std::map<uint16_t, uint64_t> U16U64Map() {
    RecordCursor m = Prefixed();
    std::map<uint16_t, uint64_t> out;
    while (!m.AtEnd()) {
      const uint16_t k = m.U16();
      out[k] = m.U64();
    }
    return out;
  }
  std::span<const std::byte> Rest() { return Bytes(data_.size() - pos_); }
  bool AtEnd() const { return pos_ == data_.size(); }
  uint64_t offset() const { return base_ + pos_; }

 private:
  void Need(uint64_t n) const {
    if (n > data_.size() - pos_) {
      throw McapError("offset " + std::to_string(base_ + pos_) + ": " + std::string(what_) +
                      " field of " + std::to_string(n) + " bytes runs past the end of the record");
    }
  }
  template <class T>
  T Le() {
    Need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::span<const std::byte> data_;
  uint64_t base_;
  std::string_view what_;
  std::size_t pos_ = 0;
};

Schema ParseSchema(RecordCursor& c);
Channel ParseChannel(RecordCursor& c);
Statistics ParseStatistics(RecordCursor& c);
ChunkIndex ParseChunkIndex(RecordCursor& c);

void AppendSchema(RecordBuilder& b, const Schema& s);
void AppendChannel(RecordBuilder& b, const Channel& c);
void AppendStatistics(RecordBuilder& b, const Statistics& s);
void AppendChunkIndex(RecordBuilder& b, const ChunkIndex& ci);

std::string OpcodeName(uint8_t opcode);

}  // namespace rslam::mcap
