// A recording cut short (SIGKILL) is repaired: every message of every complete chunk survives.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "common/mcap/mcap_recovery.h"
#include "tests/unit/mcap/mcap_test_util.h"

namespace rslam::mcap {
namespace {

using testing::DeclareChannels;
using testing::MakeMessages;
using testing::ReadAll;
using testing::ReadFile;
using testing::ScratchFolderForTest;
using testing::WriteAll;
using testing::WriteFile;

TEST(McapRecovery, TruncatedInsideAChunkKeepsEveryCompleteChunk) {
  const auto dir = ScratchFolderForTest();
  const auto msgs = MakeMessages(500);
  McapWriterOptions o;
  o.chunk_size = 16 * 1024;
  {
    McapWriter w;
    w.Open(dir / "full.mcap", o);
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Close();
  }
  const auto full = ReadFile(dir / "full.mcap");
  std::vector<ChunkInfo> chunks;
  {
    const McapReader r{std::vector<std::byte>(full)};
    chunks = r.chunks();
  }
  ASSERT_GT(chunks.size(), 6u);
  for (const std::size_t keep : {std::size_t{0}, std::size_t{1}, chunks.size() / 2,
                                 chunks.size() - 1}) {
    SCOPED_TRACE("complete chunks: " + std::to_string(keep));
    // Cut halfway through chunk `keep`, as a kill during its write would.
    const uint64_t cut = chunks[keep].offset + chunks[keep].compressed_size / 2;
    WriteFile(dir / "cut.mcap", std::span(full).first(cut));
    EXPECT_THROW(McapReader((dir / "cut.mcap").string()), McapError);

    const RecoveryReport report = RecoverMcap(dir / "cut.mcap", dir / "fixed.mcap");
    uint64_t expected = 0;
    for (std::size_t i = 0; i < keep; ++i) expected += chunks[i].message_count;
    EXPECT_EQ(report.messages, expected);
    EXPECT_EQ(report.chunks, keep);
    EXPECT_EQ(report.bytes_dropped, cut - chunks[keep].offset);

    const McapReader fixed((dir / "fixed.mcap").string());
    EXPECT_EQ(fixed.statistics().message_count, expected);
    auto got = ReadAll(fixed);
    std::sort(got.begin(), got.end(), [](auto& a, auto& b) { return a.sequence < b.sequence; });
    ASSERT_EQ(got.size(), expected);
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].sequence, msgs[i].sequence);
      EXPECT_EQ(got[i].log_time, msgs[i].log_time);
      EXPECT_TRUE(got[i].data == msgs[i].data);
    }
    if (keep > 0) {
      EXPECT_EQ(fixed.channels().size(), 3u);
      EXPECT_EQ(fixed.channels().at(2).metadata.at("robot"), "robot1");
    }
  }
}

TEST(McapRecovery, CompleteFileRecoversUnchanged) {
  const auto dir = ScratchFolderForTest();
  const auto msgs = MakeMessages(100);
  {
    McapWriter w;
    w.Open(dir / "full.mcap");
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Close();
  }
  const auto report = RecoverMcap(dir / "full.mcap", dir / "copy.mcap");
  EXPECT_EQ(report.messages, msgs.size());
  EXPECT_EQ(report.bytes_dropped, 0u);
  EXPECT_EQ(McapReader((dir / "copy.mcap").string()).statistics().message_count, msgs.size());
}

TEST(McapRecovery, FlushedChunkSurvivesWithoutClose) {
  const auto dir = ScratchFolderForTest();
  const auto msgs = MakeMessages(20);  // far less than one 4 MiB chunk
  std::vector<std::byte> unfinished;
  {
    McapWriter w;
    w.Open(dir / "live.mcap");
    DeclareChannels(w);
    WriteAll(w, msgs);
    w.Flush();
    w.Write(1, 999, 5, 5, msgs[0].data);  // still in the open chunk when "killed"
    unfinished = ReadFile(dir / "live.mcap");  // what the OS has now
  }
  WriteFile(dir / "killed.mcap", unfinished);
  const auto report = RecoverMcap(dir / "killed.mcap", dir / "fixed.mcap");
  EXPECT_EQ(report.messages, msgs.size());
  EXPECT_EQ(report.chunks, 1u);
  EXPECT_EQ(report.bytes_dropped, 0u);
}

TEST(McapRecovery, NotAnMcapFileIsRefused) {
  const auto dir = ScratchFolderForTest();
  const std::string junk = "this is not an mcap file at all";
  WriteFile(dir / "junk", std::as_bytes(std::span(junk)));
  EXPECT_THROW(RecoverMcap(dir / "junk", dir / "out.mcap"), McapError);
}

TEST(McapRecovery, RecorderKilledWithSigkillLosesAtMostTheOpenChunk) {
  const auto dir = ScratchFolderForTest();
  const auto path = dir / "killed.mcap";
  McapWriterOptions o;
  o.chunk_size = 8 * 1024;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Child: records forever; the parent kills it.
    try {
      McapWriter w;
      w.Open(path, o);
      DeclareChannels(w);
      for (uint32_t i = 0;; ++i) {
        w.Write(1 + i % 3, i, 1'000'000'000ull + i, 1'000'000'000ull + i,
                testing::Payload(i, 300));
        if (i % 64 == 0) ::usleep(100);
      }
    } catch (...) {
    }
    ::_exit(1);
  }
  for (int i = 0; i < 500 && std::filesystem::exists(path) == false; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  for (int i = 0; i < 1000; ++i) {
    std::error_code ec;
    if (std::filesystem::file_size(path, ec) > 200 * 1024) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));

  const auto report = RecoverMcap(path, dir / "fixed.mcap");
  EXPECT_GT(report.chunks, 5u);
  // What was lost is at most the open chunk (compressed, so smaller than its target size).
  EXPECT_LT(report.bytes_dropped, uint64_t(o.chunk_size) + 4096);
  const McapReader fixed((dir / "fixed.mcap").string());
  const auto got = ReadAll(fixed);
  ASSERT_EQ(got.size(), report.messages);
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].sequence, i);  // a gap-free prefix of what was written
    EXPECT_TRUE(got[i].data == testing::Payload(static_cast<uint32_t>(i), 300));
  }
}

}  // namespace
}  // namespace rslam::mcap
