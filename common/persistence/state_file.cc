#include "common/persistence/state_file.h"

#include <spdlog/spdlog.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unistd.h>
#include <fcntl.h>

namespace rslam {
namespace {

constexpr char kMagic[8] = {'R', 'S', 'L', 'A', 'M', 'P', 'B', '1'};

std::array<uint32_t, 256> MakeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

template <class T>
void Put(std::string& out, T v) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <class T>
bool Get(const std::string& in, std::size_t& pos, T& v) {
  if (in.size() - pos < sizeof(T)) return false;
  std::memcpy(&v, in.data() + pos, sizeof(T));
  pos += sizeof(T);
  return true;
}

}  // namespace

uint32_t Crc32(const void* data, std::size_t size, uint32_t crc) {
  static const std::array<uint32_t, 256> table = MakeCrcTable();
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void WriteStateFile(const std::string& path, const std::string& kind, uint32_t version,
                    const google::protobuf::MessageLite& message) {
  std::string payload;
  if (!message.SerializeToString(&payload)) throw StateFileError(path + ": cannot serialise " + kind);
  std::string out(kMagic, sizeof(kMagic));
  Put<uint32_t>(out, version);
  Put<uint32_t>(out, static_cast<uint32_t>(kind.size()));
  out += kind;
  Put<uint64_t>(out, payload.size());
  Put<uint32_t>(out, Crc32(payload.data(), payload.size()));
  out += payload;

  const std::filesystem::path target(path);
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw StateFileError(path + ": cannot open for writing: " + std::strerror(errno));
  std::size_t written = 0;
  while (written < out.size()) {
    const ssize_t n = ::write(fd, out.data() + written, out.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      throw StateFileError(path + ": write failed: " + std::strerror(errno));
    }
    written += static_cast<std::size_t>(n);
  }
  ::fsync(fd);
  ::close(fd);
  std::error_code ec;
  std::filesystem::rename(tmp, target, ec);
  if (ec) throw StateFileError(path + ": cannot rename into place: " + ec.message());
}

bool WriteStateFileOrLog(const std::string& path, const std::string& kind, uint32_t version,
                         const google::protobuf::MessageLite& message) {
  try {
    WriteStateFile(path, kind, version, message);
    return true;
  } catch (const std::exception& e) {
    spdlog::error("could not save state: {}", e.what());
    return false;
  }
}

uint32_t ReadStateFile(const std::string& path, const std::string& kind, uint32_t max_version,
                       google::protobuf::MessageLite& message) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw StateFileError(path + ": cannot open");
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string refused = path + ": refused: ";
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0)
    throw StateFileError(refused + "not an rslam state file (bad magic)");
  std::size_t pos = sizeof(kMagic);
  uint32_t version = 0, kind_size = 0, crc = 0;
  uint64_t payload_size = 0;
  if (!Get(data, pos, version) || !Get(data, pos, kind_size) || data.size() - pos < kind_size)
    throw StateFileError(refused + "truncated header");
  const std::string file_kind = data.substr(pos, kind_size);
  pos += kind_size;
  if (file_kind != kind) throw StateFileError(refused + "holds '" + file_kind + "', expected '" + kind + "'");
  if (version == 0 || version > max_version)
    throw StateFileError(refused + "format version " + std::to_string(version) + " is not supported (max " +
                         std::to_string(max_version) + ")");
  if (!Get(data, pos, payload_size) || !Get(data, pos, crc)) throw StateFileError(refused + "truncated header");
  if (data.size() - pos != payload_size)
    throw StateFileError(refused + "payload is " + std::to_string(data.size() - pos) + " bytes, header says " +
                         std::to_string(payload_size));
  if (Crc32(data.data() + pos, payload_size) != crc) throw StateFileError(refused + "CRC mismatch");
  if (!message.ParseFromArray(data.data() + pos, static_cast<int>(payload_size)))
    throw StateFileError(refused + "payload does not parse as " + kind);
  return version;
}

}  // namespace rslam
