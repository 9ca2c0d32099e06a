#pragma once
// Chunk compression as MCAP names it: "zstd" (zstd frame), "lz4" (LZ4 frame format) or ""
// (stored). The compressor keeps its codec context so each chunk costs no allocations.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rslam::mcap {

// True for "zstd", "lz4" and "".
bool IsSupportedCompression(std::string_view compression);

class ChunkCompressor {
 public:
  // Throws std::invalid_argument for an unknown compression name.
  ChunkCompressor(std::string compression, int level);
  ~ChunkCompressor();
  ChunkCompressor(const ChunkCompressor&) = delete;
  ChunkCompressor& operator=(const ChunkCompressor&) = delete;

  // Compresses input into out (resized to the compressed size). Not used for "".
  void Compress(std::span<const std::byte> input, std::vector<std::byte>& out);
  const std::string& compression() const { return compression_; }

 private:
  const std::string compression_;
  const int level_;
  void* zstd_ctx_ = nullptr;
};

// Decompresses one chunk's records into out, which must come out exactly uncompressed_size
// bytes. Throws McapError (naming chunk_offset) on unknown compression or corrupt data.
void DecompressChunk(std::string_view compression, std::span<const std::byte> input,
                     uint64_t uncompressed_size, uint64_t chunk_offset,
                     std::vector<std::byte>& out);

}  // namespace rslam::mcap
