#pragma once
// Saved state, maps and other Protobuf files, written atomically and refused whole when corrupt.
//
// Layout: "RSLAMPB1" magic, u32 format version, u32 length of kind, kind (e.g.
// "rslam.pose_cells.State"), u64 payload length, u32 CRC-32 of the payload, payload (the
// Protobuf message). Little-endian. A file is written to a temporary name, flushed and renamed,
// so a crash mid-write leaves the previous file intact.

#include <google/protobuf/message_lite.h>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace rslam {

class StateFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes message as a file of the given kind and version. Throws StateFileError on I/O errors.
void WriteStateFile(const std::string& path, const std::string& kind, uint32_t version,
                    const google::protobuf::MessageLite& message);

// The same for a service's periodic and shutdown saves: a failure (disk full, folder gone) is
// logged, not thrown, and false returned so the caller keeps its state marked unsaved and tries
// again at the next save.
bool WriteStateFileOrLog(const std::string& path, const std::string& kind, uint32_t version,
                         const google::protobuf::MessageLite& message);

// Reads a file written by WriteStateFile into message. Refuses (throws StateFileError naming the
// path and the reason) a missing file, wrong magic, another kind, a version newer than
// max_version, a length or CRC mismatch, or a payload that does not parse. Returns the version.
uint32_t ReadStateFile(const std::string& path, const std::string& kind, uint32_t max_version,
                       google::protobuf::MessageLite& message);

// CRC-32 (IEEE 802.3, as zlib and MCAP use).
uint32_t Crc32(const void* data, std::size_t size, uint32_t crc = 0);

}  // namespace rslam
