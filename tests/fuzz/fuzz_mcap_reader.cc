// libFuzzer target: arbitrary bytes given to McapReader (in memory) and to RecoverMcap (through
// memfds). Either may refuse the input with McapError; nothing may crash, hang, leak or allocate
// beyond the reader's limits. Any other exception escapes and is reported as a crash.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/mcap/mcap_reader.h"
#include "common/mcap/mcap_recovery.h"

namespace {

int MemFd(const char* name) { return ::memfd_create(name, MFD_CLOEXEC); }

void FuzzReader(const uint8_t* data, size_t size, bool verify_crcs) {
  rslam::mcap::McapReaderOptions options;
  options.max_chunk_uncompressed_bytes = 8 << 20;
  options.verify_crcs = verify_crcs;
  try {
    const rslam::mcap::McapReader reader(
        std::vector<std::byte>(reinterpret_cast<const std::byte*>(data),
                               reinterpret_cast<const std::byte*>(data) + size),
        options);
    uint64_t sum = 0;
    reader.ForEachMessage({}, [&](const rslam::mcap::MessageView& v) {
      for (std::byte b : v.data) sum += static_cast<uint8_t>(b);
      sum += v.channel->topic.size();
    });
    // A file that opened must be self-consistent.
    uint64_t count = 0;
    reader.ForEachMessage({}, [&](const rslam::mcap::MessageView&) { ++count; });
    if (count != reader.statistics().message_count) __builtin_trap();
  } catch (const rslam::mcap::McapError&) {
  }
}

void FuzzRecovery(const uint8_t* data, size_t size) {
  const int in = MemFd("in");
  const int out = MemFd("out");
  if (in < 0 || out < 0) __builtin_trap();
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(in, data + done, size - done);
    if (n <= 0) __builtin_trap();
    done += static_cast<size_t>(n);
  }
  const std::string in_path = "/proc/self/fd/" + std::to_string(in);
  const std::string out_path = "/proc/self/fd/" + std::to_string(out);
  try {
    rslam::mcap::McapWriterOptions writer_options;
    writer_options.chunk_size = 64 << 10;  // small buffers keep the fuzzer fast
    const auto report = rslam::mcap::RecoverMcap(in_path, out_path, writer_options, true, 8 << 20);
    // Whatever was recovered must be a valid file with exactly those messages.
    rslam::mcap::McapReaderOptions options;
    options.max_chunk_uncompressed_bytes = 8 << 20;
    const rslam::mcap::McapReader fixed(out_path, options);
    if (fixed.statistics().message_count != report.messages) __builtin_trap();
  } catch (const rslam::mcap::McapError&) {
  }
  ::close(in);
  ::close(out);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzReader(data, size, true);
  // Without CRCs, mutated chunk contents reach the record parsers instead of being refused early.
  FuzzReader(data, size, false);
  FuzzRecovery(data, size);
  return 0;
}
