// Writes a few small, valid MCAP files (each compression, with and without messages, one cut
// short) as the fuzzer's seed corpus. Usage: make_seed_corpus <dir>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/mcap/mcap_writer.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <corpus dir>\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  int file = 0;
  for (const std::string compression : {"zstd", "lz4", ""}) {
    for (const int messages : {0, 3, 40}) {
      rslam::mcap::McapWriterOptions o;
      o.compression = compression;
      o.chunk_size = 1024;
      rslam::mcap::McapWriter w;
      const auto path = dir / ("seed_" + std::to_string(file++) + ".mcap");
      w.Open(path.string(), o);
      const uint16_t s = w.AddSchema("rslam::msg::Ping", "omgidl",
                                     "module rslam { module msg { struct Ping { uint32 seq; }; }; };");
      const uint16_t a = w.AddChannel(s, "/a", "cdr", {{"robot", "r1"}, {"qos", "reliable"}});
      const uint16_t b = w.AddChannel(0, "/b", "cdr", {});
      for (int i = 0; i < messages; ++i) {
        std::vector<std::byte> d(4 + (i * 7) % 90, std::byte(i));
        d[1] = std::byte{1};
        w.Write(i % 2 ? a : b, i, 1000 + 10 * i - (i % 3), 1000 + 10 * i, d);
      }
      w.Close();
      if (messages == 40) {
        // A recording cut short, as after SIGKILL.
        const auto cut = dir / ("seed_" + std::to_string(file++) + "_cut.mcap");
        std::filesystem::copy_file(path, cut, std::filesystem::copy_options::overwrite_existing);
        std::filesystem::resize_file(cut, std::filesystem::file_size(path) * 2 / 3);
      }
    }
  }
  return 0;
}
