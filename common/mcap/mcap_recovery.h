#pragma once
// Repairs an MCAP file left unfinished by a killed recorder (complete chunks, then a partial
// chunk, no Data End, summary or footer): writes a new, valid file with every message of every
// complete record (chunks whose records decompress and pass their CRC) and drops the rest.
// Also works on a complete file (then nothing is dropped).

#include <cstdint>
#include <string>

#include "common/mcap/mcap_writer.h"

namespace rslam::mcap {

struct RecoveryReport {
  uint64_t messages = 0;       // messages written to the repaired file
  uint64_t chunks = 0;         // complete chunks recovered
  uint64_t bytes_dropped = 0;  // bytes after the last complete data record (0 if it had Data End)
};

// Reads in_path, writes out_path (must differ) with the given writer options; when
// keep_input_compression is set, the output uses the compression of the input's first chunk.
// Schema and channel ids may be renumbered; topics, metadata, sequences and times are kept.
// Throws McapError if in_path does not start with MCAP magic and a complete Header.
// Chunks claiming more than max_chunk_uncompressed_bytes are treated as damage (the end).
RecoveryReport RecoverMcap(const std::string& in_path, const std::string& out_path,
                           const McapWriterOptions& options = {},
                           bool keep_input_compression = true,
                           uint64_t max_chunk_uncompressed_bytes = uint64_t{1} << 30);

}  // namespace rslam::mcap
