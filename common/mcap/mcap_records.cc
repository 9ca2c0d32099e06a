#include "common/mcap/mcap_records.h"

namespace rslam::mcap {

Schema ParseSchema(RecordCursor& c) {
  Schema s;
  s.id = c.U16();
  s.name = c.String();
  s.encoding = c.String();
  const auto data = c.Bytes(c.U32());
  s.data.assign(reinterpret_cast<const char*>(data.data()), data.size());
  return s;
}

Channel ParseChannel(RecordCursor& c) {
  Channel ch;
  ch.id = c.U16();
  ch.schema_id = c.U16();
  ch.topic = c.String();
  ch.message_encoding = c.String();
  ch.metadata = c.StringMap();
  return ch;
}

Statistics ParseStatistics(RecordCursor& c) {
  Statistics s;
  s.message_count = c.U64();
  s.schema_count = c.U16();
  s.channel_count = c.U32();
  s.attachment_count = c.U32();
  s.metadata_count = c.U32();
  s.chunk_count = c.U32();
  s.message_start_time = c.U64();
  s.message_end_time = c.U64();
  s.channel_message_counts = c.U16U64Map();
  return s;
}

ChunkIndex ParseChunkIndex(RecordCursor& c) {
  ChunkIndex ci;
  ci.message_start_time = c.U64();
  ci.message_end_time = c.U64();
  ci.chunk_start_offset = c.U64();
  ci.chunk_length = c.U64();
  ci.message_index_offsets = c.U16U64Map();
  ci.message_index_length = c.U64();
  ci.compression = c.String();
  ci.compressed_size = c.U64();
  ci.uncompressed_size = c.U64();
  return ci;
}

void AppendSchema(RecordBuilder& b, const Schema& s) {
  const auto r = b.BeginRecord(Opcode::kSchema);
  b.U16(s.id);
  b.String(s.name);
  b.String(s.encoding);
  b.String(s.data);  // u32-length-prefixed bytes: same layout as a string
  b.EndRecord(r);
}

void AppendChannel(RecordBuilder& b, const Channel& c) {
  const auto r = b.BeginRecord(Opcode::kChannel);
  b.U16(c.id);
  b.U16(c.schema_id);
  b.String(c.topic);
  b.String(c.message_encoding);
  const auto m = b.BeginPrefixed();
  for (const auto& [k, v] : c.metadata) {
    b.String(k);
    b.String(v);
  }
  b.EndPrefixed(m);
  b.EndRecord(r);
}

void AppendStatistics(RecordBuilder& b, const Statistics& s) {
  const auto r = b.BeginRecord(Opcode::kStatistics);
  b.U64(s.message_count);
  b.U16(s.schema_count);
  b.U32(s.channel_count);
  b.U32(s.attachment_count);
  b.U32(s.metadata_count);
  b.U32(s.chunk_count);
  b.U64(s.message_start_time);
  b.U64(s.message_end_time);
  const auto m = b.BeginPrefixed();
  for (const auto& [k, v] : s.channel_message_counts) {
    b.U16(k);
    b.U64(v);
  }
  b.EndPrefixed(m);
  b.EndRecord(r);
}

void AppendChunkIndex(RecordBuilder& b, const ChunkIndex& ci) {
  const auto r = b.BeginRecord(Opcode::kChunkIndex);
  b.U64(ci.message_start_time);
  b.U64(ci.message_end_time);
  b.U64(ci.chunk_start_offset);
  b.U64(ci.chunk_length);
  const auto m = b.BeginPrefixed();
  for (const auto& [k, v] : ci.message_index_offsets) {
    b.U16(k);
    b.U64(v);
  }
  b.EndPrefixed(m);
  b.U64(ci.message_index_length);
  b.String(ci.compression);
  b.U64(ci.compressed_size);
  b.U64(ci.uncompressed_size);
  b.EndRecord(r);
}

std::string OpcodeName(uint8_t opcode) {
  static constexpr const char* kNames[] = {
      "invalid(0x00)", "Header",     "Footer",          "Schema",     "Channel",
      "Message",       "Chunk",      "MessageIndex",    "ChunkIndex", "Attachment",
      "AttachmentIndex", "Statistics", "Metadata",      "MetadataIndex", "SummaryOffset",
      "DataEnd"};
  if (opcode < std::size(kNames)) return kNames[opcode];
  char buf[32];
  std::snprintf(buf, sizeof(buf), "opcode 0x%02X", opcode);
  return buf;
}

}  // namespace rslam::mcap
