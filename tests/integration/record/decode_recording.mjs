// Decodes every message of an rslam recording with the official Foxglove packages only:
// @mcap/core (indexed reader, CRCs validated) + @mcap/nodejs + @mcap/support (zstd/lz4) read the
// file, @foxglove/omgidl-parser parses each channel's schema (the IDL text stored in the file)
// and @foxglove/omgidl-serialization decodes the CDR with it. Prints JSON for the C++ test:
//   {statistics: {message_count, channel_message_counts}, channels: [...],
//    messages: [{topic, dds_topic, robot, schema, sequence, decoded}]}
// Byte arrays are reported as {length, crc32}, 64-bit integers as decimal strings.
//
// Usage: NODE_PATH=<dir>/node_modules node decode_recording.mjs <file.mcap>
import { createRequire } from "node:module";
import { open } from "node:fs/promises";
import zlib from "node:zlib";
import path from "node:path";

const require = createRequire(path.join(process.env.NODE_PATH ?? ".", "noop.js"));
const { McapIndexedReader } = require("@mcap/core");
const { FileHandleReadable } = require("@mcap/nodejs");
const { loadDecompressHandlers } = require("@mcap/support");
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

function plain(v) {
  if (v instanceof Uint8Array) return { length: v.byteLength, crc32: zlib.crc32(v) };
  if (typeof v === "bigint") return v.toString();
  if (ArrayBuffer.isView(v)) return Array.from(v, plain);
  if (Array.isArray(v)) return v.map(plain);
  if (v && typeof v === "object") return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, plain(x)]));
  return v;
}

const handle = await open(process.argv[2], "r");
const reader = await McapIndexedReader.Initialize({
  readable: new FileHandleReadable(handle),
  decompressHandlers: await loadDecompressHandlers(),
});
const readers = new Map();  // schema id -> MessageReader built from the file's own IDL
const out = { statistics: null, channels: [], messages: [] };
if (reader.statistics) {
  out.statistics = {
    message_count: Number(reader.statistics.messageCount),
    channel_message_counts: Object.fromEntries(
      [...reader.statistics.channelMessageCounts].map(([k, v]) => [k, Number(v)])),
  };
}
for (const c of reader.channelsById.values()) {
  const schema = reader.schemasById.get(c.schemaId);
  out.channels.push({ id: c.id, topic: c.topic, schema: schema.name, schema_encoding: schema.encoding,
                      message_encoding: c.messageEncoding, metadata: Object.fromEntries(c.metadata) });
}
for await (const m of reader.readMessages({ validateCrcs: true })) {
  const channel = reader.channelsById.get(m.channelId);
  const schema = reader.schemasById.get(channel.schemaId);
  if (!readers.has(schema.id)) {
    readers.set(schema.id, new MessageReader(schema.name, parseIDL(new TextDecoder().decode(schema.data))));
  }
  out.messages.push({
    topic: channel.topic, dds_topic: channel.metadata.get("dds_topic"), robot: channel.metadata.get("robot"),
    schema: schema.name, sequence: m.sequence, decoded: plain(readers.get(schema.id).readMessage(m.data)),
  });
}
await handle.close();
process.stdout.write(JSON.stringify(out));
