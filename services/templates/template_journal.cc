#include "services/templates/template_journal.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "common/persistence/state_file.h"

namespace rslam::templates {
namespace {

constexpr uint32_t kRecordMagic = 0x4A545352;  // "RSTJ" little-endian
constexpr std::size_t kRecordHeader = 12;
constexpr uint32_t kMaxRecordBytes = 64u << 20;  // far above any template (at most 1 Mpixel)

uint32_t LoadU32(const char* p) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<uint8_t>(p[i]);
  return v;
}

void StoreU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

[[noreturn]] void Fail(const std::string& path, const std::string& what) {
  throw StateFileError(path + ": " + what + (errno ? std::string(" (") + std::strerror(errno) + ")" : ""));
}

}  // namespace

TemplateJournal::Contents TemplateJournal::Read(const std::string& path) {
  Contents contents;
  std::ifstream in(path, std::ios::binary);
  if (!in) return contents;
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t at = 0;
  while (at < bytes.size()) {
    const std::size_t left = bytes.size() - at;
    const auto refuse = [&](const std::string& reason) {
      throw StateFileError(path + ": corrupt template journal at byte " + std::to_string(at) + ": " + reason);
    };
    if (left < kRecordHeader) {
      contents.torn_tail = true;  // header cut short by a crash
      break;
    }
    const uint32_t magic = LoadU32(bytes.data() + at);
    const uint32_t length = LoadU32(bytes.data() + at + 4);
    const uint32_t crc = LoadU32(bytes.data() + at + 8);
    if (magic != kRecordMagic) {
      // A crash after the file grew but before its data reached the disk leaves zeros at the
      // end; anything else is corruption.
      if (bytes.find_first_not_of('\0', at) == std::string::npos) {
        contents.torn_tail = true;
        break;
      }
      refuse("bad record magic");
    }
    if (length > kMaxRecordBytes) refuse("record length " + std::to_string(length));
    if (left < kRecordHeader + length) {
      contents.torn_tail = true;  // payload cut short
      break;
    }
    const char* payload = bytes.data() + at + kRecordHeader;
    proto::Template t;
    const bool intact = Crc32(payload, length) == crc && t.ParseFromArray(payload, static_cast<int>(length));
    if (!intact) {
      if (at + kRecordHeader + length == bytes.size()) {
        contents.torn_tail = true;  // the last record, partly written
        break;
      }
      refuse("record checksum or payload mismatch before the last record");
    }
    contents.templates.push_back(std::move(t));
    at += kRecordHeader + length;
    contents.valid_bytes = at;
  }
  return contents;
}

TemplateJournal::TemplateJournal(std::string path, uint64_t valid_bytes, bool sync)
    : path_(std::move(path)), sync_(sync) {
  errno = 0;
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) Fail(path_, "cannot open the template journal");
  if (::ftruncate(fd_, static_cast<off_t>(valid_bytes)) != 0) Fail(path_, "cannot cut the torn tail");
  if (::lseek(fd_, 0, SEEK_END) < 0) Fail(path_, "cannot seek");
  if (sync_ && ::fsync(fd_) != 0) Fail(path_, "fsync failed");
}

TemplateJournal::~TemplateJournal() {
  if (fd_ >= 0) ::close(fd_);
}

void TemplateJournal::Append(const proto::Template& t) {
  std::string payload;
  if (!t.SerializeToString(&payload)) Fail(path_, "cannot serialise a template");
  buffer_.clear();
  StoreU32(buffer_, kRecordMagic);
  StoreU32(buffer_, static_cast<uint32_t>(payload.size()));
  StoreU32(buffer_, Crc32(payload.data(), payload.size()));
  buffer_ += payload;
  std::size_t written = 0;
  errno = 0;
  while (written < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + written, buffer_.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) Fail(path_, "cannot append to the template journal");
    written += static_cast<std::size_t>(n);
  }
  if (sync_ && ::fdatasync(fd_) != 0) Fail(path_, "fdatasync failed");
}

void TemplateJournal::Clear() {
  errno = 0;
  if (::ftruncate(fd_, 0) != 0) Fail(path_, "cannot clear the template journal");
  if (::lseek(fd_, 0, SEEK_SET) < 0) Fail(path_, "cannot seek");
  if (sync_ && ::fsync(fd_) != 0) Fail(path_, "fsync failed");
}

}  // namespace rslam::templates
