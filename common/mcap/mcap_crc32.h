#pragma once
// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib and MCAP use), slicing-by-8.
// Same values as rslam::Crc32 in common/persistence/state_file.h, about 5x faster: the writer
// checksums every uncompressed chunk and the whole data section, so the byte-wise table would
// cost a fifth of the recording budget.

#include <cstddef>
#include <cstdint>

namespace rslam::mcap {

// Continues a CRC: Crc32(b, nb, Crc32(a, na)) == Crc32(a ++ b).
uint32_t Crc32(const void* data, std::size_t size, uint32_t crc = 0);

}  // namespace rslam::mcap
