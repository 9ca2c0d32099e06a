// A damaged file is refused whole, with an McapError that says where and what.
#include <gtest/gtest.h>

#include "tests/unit/mcap/mcap_test_util.h"

namespace rslam::mcap {
namespace {

using testing::DeclareChannels;
using testing::MakeMessages;
using testing::ReadFile;
using testing::ScratchFolderForTest;
using testing::WriteAll;

std::vector<std::byte> GoodFile(const std::string& compression) {
  const auto path = ScratchFolderForTest() / "good.mcap";
  McapWriter w;
  McapWriterOptions o;
  o.compression = compression;
  o.chunk_size = 16 * 1024;
  w.Open(path, o);
  DeclareChannels(w);
  WriteAll(w, MakeMessages(200));
  w.Close();
  return ReadFile(path);
}

// The McapError message of opening bytes, or "" if it opened.
std::string OpenError(std::vector<std::byte> bytes) {
  try {
    McapReader r(std::move(bytes));
    return "";
  } catch (const McapError& e) {
    return e.what();
  }
}

uint64_t FirstChunkOffset(const std::vector<std::byte>& file) {
  const McapReader r{std::vector<std::byte>(file)};
  return r.chunks().at(0).offset;
}

TEST(McapCorruption, GoodFileOpens) { EXPECT_EQ(OpenError(GoodFile("zstd")), ""); }

TEST(McapCorruption, TruncatedFileIsRefusedAtEveryCut) {
  const auto file = GoodFile("zstd");
  for (const std::size_t cut : {std::size_t{0}, std::size_t{5}, std::size_t{8}, std::size_t{30},
                                file.size() / 3, file.size() / 2, file.size() - 100,
                                file.size() - 30, file.size() - 9, file.size() - 1}) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    const std::string err = OpenError(std::vector<std::byte>(file.begin(), file.begin() + cut));
    EXPECT_NE(err, "");
    EXPECT_NE(err.find("offset"), std::string::npos) << err;
  }
  const std::string err =
      OpenError(std::vector<std::byte>(file.begin(), file.begin() + file.size() / 2));
  EXPECT_NE(err.find("RecoverMcap"), std::string::npos) << err;
}

TEST(McapCorruption, WrongMagicIsRefused) {
  auto file = GoodFile("zstd");
  file[1] = std::byte{'X'};
  EXPECT_NE(OpenError(file).find("magic"), std::string::npos);
  auto tail = GoodFile("zstd");
  tail[tail.size() - 3] = std::byte{'X'};
  EXPECT_NE(OpenError(tail).find("closing magic"), std::string::npos);
}

TEST(McapCorruption, FlippedByteInUncompressedChunkFailsItsCrc) {
  auto file = GoodFile("");
  const uint64_t chunk = FirstChunkOffset(file);
  // Well inside the chunk's records (past its 9-byte prefix and 48-byte fixed fields).
  file[chunk + 400] ^= std::byte{0x40};
  const std::string err = OpenError(file);
  EXPECT_NE(err.find("CRC"), std::string::npos) << err;
  EXPECT_NE(err.find("offset " + std::to_string(chunk)), std::string::npos) << err;
}

TEST(McapCorruption, FlippedByteInCompressedChunkIsRefused) {
  for (const std::string compression : {"zstd", "lz4"}) {
    auto file = GoodFile(compression);
    const uint64_t chunk = FirstChunkOffset(file);
    file[chunk + 300] ^= std::byte{0x01};
    const std::string err = OpenError(file);
    EXPECT_NE(err, "") << compression;
    EXPECT_NE(err.find("Chunk"), std::string::npos) << compression << ": " << err;
  }
}

TEST(McapCorruption, RecordLengthPastTheEndIsRefused) {
  auto file = GoodFile("zstd");
  const uint64_t chunk = FirstChunkOffset(file);
  const uint64_t huge = uint64_t{1} << 40;
  std::memcpy(file.data() + chunk + 1, &huge, 8);
  const std::string err = OpenError(file);
  EXPECT_NE(err.find("record length"), std::string::npos) << err;
  EXPECT_NE(err.find("offset " + std::to_string(chunk)), std::string::npos) << err;
}

TEST(McapCorruption, ShortenedRecordLengthIsRefused) {
  auto file = GoodFile("zstd");
  const uint64_t chunk = FirstChunkOffset(file);
  uint64_t len;
  std::memcpy(&len, file.data() + chunk + 1, 8);
  len -= 5;
  std::memcpy(file.data() + chunk + 1, &len, 8);
  EXPECT_NE(OpenError(file), "");
}

TEST(McapCorruption, FlippedByteInSummaryFailsTheSummaryCrc) {
  auto file = GoodFile("zstd");
  // Footer: summary_start is 8 bytes after the footer opcode+length.
  const std::size_t footer = file.size() - 8 - 29;
  uint64_t summary_start;
  std::memcpy(&summary_start, file.data() + footer + 9, 8);
  file[summary_start + 20] ^= std::byte{0x01};
  const std::string err = OpenError(file);
  EXPECT_NE(err.find("summary CRC"), std::string::npos) << err;
}

TEST(McapCorruption, InvalidOpcodeIsRefused) {
  auto file = GoodFile("zstd");
  file[FirstChunkOffset(file)] = std::byte{0};
  EXPECT_NE(OpenError(file).find("opcode"), std::string::npos);
}

TEST(McapCorruption, MissingFileIsAnError) {
  EXPECT_THROW(McapReader("/nonexistent/x.mcap"), std::runtime_error);
}

}  // namespace
}  // namespace rslam::mcap
