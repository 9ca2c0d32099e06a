#pragma once
// A DDS domain id of the test's own, so tests running in parallel (ctest -j) never see each
// other's traffic. Ids come from 100-229 and are held by an flock on a file in /tmp for the
// life of the object (a crashed test releases its lock with its process).

#include <string>

namespace rslam::testing {

class TestDomain {
 public:
  TestDomain();
  ~TestDomain();
  TestDomain(const TestDomain&) = delete;
  TestDomain& operator=(const TestDomain&) = delete;

  int id() const { return id_; }

 private:
  int id_ = -1;
  int fd_ = -1;
};

// $RSLAM_SHARED_DATA (the shared data folder), or "" when it is absent.
std::string SharedDataDir();

}  // namespace rslam::testing
