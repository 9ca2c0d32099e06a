#include "common/mcap/chunk_compression.h"

#include <lz4frame.h>
#include <zstd.h>

#include <stdexcept>

#include "common/mcap/mcap_records.h"

namespace rslam::mcap {

bool IsSupportedCompression(std::string_view compression) {
  return compression.empty() || compression == "zstd" || compression == "lz4";
}

ChunkCompressor::ChunkCompressor(std::string compression, int level)
    : compression_(std::move(compression)), level_(level) {
  if (!IsSupportedCompression(compression_)) {
    throw std::invalid_argument("unknown MCAP chunk compression '" + compression_ +
                                "' (use zstd, lz4 or empty)");
  }
  if (compression_ == "zstd") {
    zstd_ctx_ = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(static_cast<ZSTD_CCtx*>(zstd_ctx_), ZSTD_c_compressionLevel, level_);
    ZSTD_CCtx_setParameter(static_cast<ZSTD_CCtx*>(zstd_ctx_), ZSTD_c_contentSizeFlag, 1);
  }
}

ChunkCompressor::~ChunkCompressor() {
  if (zstd_ctx_) ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(zstd_ctx_));
}

void ChunkCompressor::Compress(std::span<const std::byte> input, std::vector<std::byte>& out) {
  if (compression_ == "zstd") {
    out.resize(ZSTD_compressBound(input.size()));
    const std::size_t n = ZSTD_compress2(static_cast<ZSTD_CCtx*>(zstd_ctx_), out.data(),
                                         out.size(), input.data(), input.size());
    if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
    out.resize(n);
  } else if (compression_ == "lz4") {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = input.size();
    prefs.frameInfo.blockSizeID = LZ4F_max4MB;
    prefs.compressionLevel = level_ > 0 ? 0 : level_;  // 0 = fast mode; negative = faster
    out.resize(LZ4F_compressFrameBound(input.size(), &prefs));
    const std::size_t n =
        LZ4F_compressFrame(out.data(), out.size(), input.data(), input.size(), &prefs);
    if (LZ4F_isError(n)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(n));
    out.resize(n);
  } else {
    out.assign(input.begin(), input.end());
  }
}

void DecompressChunk(std::string_view compression, std::span<const std::byte> input,
                     uint64_t uncompressed_size, uint64_t chunk_offset,
                     std::vector<std::byte>& out) {
  const std::string where = "offset " + std::to_string(chunk_offset) + ": Chunk ";
  out.resize(uncompressed_size);
  if (compression.empty()) {
    if (input.size() != uncompressed_size) {
      throw McapError(where + "is uncompressed but its records are " +
                      std::to_string(input.size()) + " bytes, not uncompressed_size " +
                      std::to_string(uncompressed_size));
    }
    if (!input.empty()) std::memcpy(out.data(), input.data(), input.size());
    return;
  }
  if (compression == "zstd") {
    const unsigned long long frame = ZSTD_getFrameContentSize(input.data(), input.size());
    if (frame == ZSTD_CONTENTSIZE_ERROR) throw McapError(where + "zstd data is not a zstd frame");
    if (frame != ZSTD_CONTENTSIZE_UNKNOWN && frame != uncompressed_size) {
      throw McapError(where + "zstd frame holds " + std::to_string(frame) +
                      " bytes, not uncompressed_size " + std::to_string(uncompressed_size));
    }
    const std::size_t n = ZSTD_decompress(out.data(), out.size(), input.data(), input.size());
    if (ZSTD_isError(n)) throw McapError(where + "zstd data corrupt: " + ZSTD_getErrorName(n));
    if (n != uncompressed_size) {
      throw McapError(where + "zstd data decompressed to " + std::to_string(n) +
                      " bytes, not uncompressed_size " + std::to_string(uncompressed_size));
    }
    return;
  }
  if (compression == "lz4") {
    LZ4F_dctx* dctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&dctx, LZ4F_VERSION))) {
      throw std::runtime_error("lz4: cannot create context");
    }
    std::size_t in_pos = 0, out_pos = 0;
    std::size_t hint = 1;
    while (in_pos < input.size() && hint != 0) {
      std::size_t in_n = input.size() - in_pos;
      std::size_t out_n = out.size() - out_pos;
      hint = LZ4F_decompress(dctx, out.data() + out_pos, &out_n, input.data() + in_pos, &in_n,
                             nullptr);
      if (LZ4F_isError(hint)) {
        LZ4F_freeDecompressionContext(dctx);
        throw McapError(where + "lz4 data corrupt: " + LZ4F_getErrorName(hint));
      }
      in_pos += in_n;
      out_pos += out_n;
      if (in_n == 0 && out_n == 0) break;  // no progress: output full or input exhausted
    }
    LZ4F_freeDecompressionContext(dctx);
    if (hint != 0 || out_pos != uncompressed_size) {
      throw McapError(where + "lz4 frame incomplete or of the wrong size (" +
                      std::to_string(out_pos) + " of " + std::to_string(uncompressed_size) +
                      " bytes)");
    }
    return;
  }
  throw McapError(where + "uses unsupported compression '" + std::string(compression) + "'");
}

}  // namespace rslam::mcap
