#include "tests/support/test_domain.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <stdexcept>

namespace rslam::testing {

TestDomain::TestDomain() {
  constexpr int kFirst = 100, kCount = 130;
  // Start at a random id so parallel tests rarely contend for the same lock.
  std::random_device rd;
  const int start = static_cast<int>(rd() % kCount);
  for (int i = 0; i < kCount; ++i) {
    const int id = kFirst + (start + i) % kCount;
    const std::string path = "/tmp/rslam-test-domain-" + std::to_string(id) + ".lock";
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      id_ = id;
      fd_ = fd;
      return;
    }
    ::close(fd);
  }
  throw std::runtime_error("no free test DDS domain id in 100-229");
}

TestDomain::~TestDomain() {
  if (fd_ >= 0) ::close(fd_);
}

std::string SharedDataDir() {
  const char* dir = std::getenv("RSLAM_SHARED_DATA");
  if (dir == nullptr || !std::filesystem::is_directory(dir)) return "";
  return dir;
}

}  // namespace rslam::testing
