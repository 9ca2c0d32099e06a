// Reads an MCAP file with the official Foxglove readers (@mcap/core, @mcap/nodejs,
// @mcap/support) and prints what it found as JSON, so the C++ test can compare it with what
// rslam's McapWriter wrote. Two independent passes: the indexed reader (footer -> summary ->
// chunk indexes -> message indexes) and the streaming reader (every record in order, CRCs on).
//
// With --decode-cdr, messages whose schema is OMG IDL are also decoded from CDR with
// @foxglove/omgidl-parser + @foxglove/omgidl-serialization (byte arrays reported as length+CRC).
//
// Usage: NODE_PATH=<dir>/node_modules node read_mcap.mjs <file.mcap> [--decode-cdr]
import { createRequire } from "node:module";
import { open, readFile } from "node:fs/promises";
import zlib from "node:zlib";
import path from "node:path";

const require = createRequire(path.join(process.env.NODE_PATH ?? ".", "noop.js"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { FileHandleReadable } = require("@mcap/nodejs");
const { loadDecompressHandlers } = require("@mcap/support");

const file = process.argv[2];
const decodeCdr = process.argv.includes("--decode-cdr");
const cdrReaders = new Map();  // schema id -> MessageReader
function cdrReaderFor(schema) {
  if (!cdrReaders.has(schema.id)) {
    const { parseIDL } = require("@foxglove/omgidl-parser");
    const { MessageReader } = require("@foxglove/omgidl-serialization");
    cdrReaders.set(schema.id, new MessageReader(schema.name, parseIDL(new TextDecoder().decode(schema.data))));
  }
  return cdrReaders.get(schema.id);
}
// JSON-friendly decoded value: byte arrays become {length, crc32}, bigints strings.
function plain(v) {
  if (v instanceof Uint8Array) return { length: v.byteLength, crc32: zlib.crc32(v) };
  if (typeof v === "bigint") return v.toString();
  if (ArrayBuffer.isView(v)) return Array.from(v, plain);
  if (Array.isArray(v)) return v.map(plain);
  if (v && typeof v === "object") return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, plain(x)]));
  return v;
}
const decompressHandlers = await loadDecompressHandlers();

const handle = await open(file, "r");
const reader = await McapIndexedReader.Initialize({
  readable: new FileHandleReadable(handle),
  decompressHandlers,
});
const out = {
  profile: reader.header.profile,
  library: reader.header.library,
  schemas: [],
  channels: [],
  statistics: null,
  chunk_compressions: reader.chunkIndexes.map((c) => c.compression),
  messages: [],
  stream_message_count: 0,
  stream_crc_sum: 0,
};
for (const s of reader.schemasById.values()) {
  out.schemas.push({ id: s.id, name: s.name, encoding: s.encoding, data: new TextDecoder().decode(s.data) });
}
for (const c of reader.channelsById.values()) {
  out.channels.push({
    id: c.id, schema_id: c.schemaId, topic: c.topic, message_encoding: c.messageEncoding,
    metadata: Object.fromEntries(c.metadata),
  });
}
if (reader.statistics) {
  const s = reader.statistics;
  out.statistics = {
    message_count: Number(s.messageCount),
    chunk_count: s.chunkCount,
    message_start_time: s.messageStartTime.toString(),
    message_end_time: s.messageEndTime.toString(),
    channel_message_counts: Object.fromEntries([...s.channelMessageCounts].map(([k, v]) => [k, Number(v)])),
  };
}
for await (const m of reader.readMessages({ validateCrcs: true })) {
  const entry = {
    channel: m.channelId, sequence: m.sequence,
    log_time: m.logTime.toString(), publish_time: m.publishTime.toString(),
    size: m.data.byteLength, crc32: zlib.crc32(m.data),
  };
  const schema = reader.schemasById.get(reader.channelsById.get(m.channelId).schemaId);
  if (decodeCdr && schema && schema.encoding === "omgidl") {
    entry.decoded = plain(cdrReaderFor(schema).readMessage(m.data));
  }
  out.messages.push(entry);
}
await handle.close();

// Streaming pass: every record, CRCs validated, must reach the footer and closing magic.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(new Uint8Array(await readFile(file)));
let sawFooter = false;
for (let r; (r = stream.nextRecord()); ) {
  if (r.type === "Message") {
    out.stream_message_count += 1;
    out.stream_crc_sum = (out.stream_crc_sum + zlib.crc32(r.data)) % 4294967296;
  }
  if (r.type === "Footer") sawFooter = true;
}
if (!stream.done() || !sawFooter) throw new Error("stream reader did not reach the end of the file");
process.stdout.write(JSON.stringify(out));
