#pragma once
// A program run as a child process for tests that start real binaries (services, `rslam`
// subcommands): stdout and stderr go to a log file, extra environment variables are added to the
// test's own, and the destructor always ends the child (SIGTERM, then SIGKILL after a grace
// period) and reaps it, so a failing test never leaves a process behind.
//
//   ChildProcess odometry(bin + "rslam-odometry", {"--domain", "123", "--config", yaml});
//   ...
//   EXPECT_EQ(odometry.Stop(), 0) << odometry.Output();   // SIGTERM, clean exit code 0
//
// Also: WaitFor (poll a condition with a deadline), ScratchFolder (a temporary folder) and
// ScratchFolderForTest (an empty folder for the running GoogleTest test).

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rslam::testing {

// Polls condition every few milliseconds until it holds or timeout passes; returns whether it held.
bool WaitFor(const std::function<bool()>& condition, std::chrono::milliseconds timeout);

// Waits until each count (matched endpoints of a test's publisher or subscriber) rises above the
// lowest it has shown since the call: a process started just before has matched, whether or not
// one that just exited is still counted when the call begins (it may leave meanwhile).
bool WaitForNewMatches(const std::vector<std::function<int()>>& counts, std::chrono::milliseconds timeout);

// A fresh temporary folder (under $TMPDIR), removed with everything in it with the object.
class ScratchFolder {
 public:
  explicit ScratchFolder(const std::string& prefix = "rslam-test");
  ~ScratchFolder();
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// An empty folder named after the running GoogleTest test, inside one ScratchFolder per test
// process, which is removed with everything in it when the process ends.
std::filesystem::path ScratchFolderForTest();

class ChildProcess {
 public:
  struct Options {
    std::map<std::string, std::string> environment;  // added to (or replacing) the test's own
    std::string log_file;                              // "" = a temporary file removed at the end
    std::chrono::milliseconds stop_grace{5000};        // SIGTERM -> SIGKILL in the destructor
    // The child leads its own process group and Signal/Stop reach the whole group: for a
    // launcher (`rslam demo`), so the processes it started end with it even if it is killed.
    bool own_process_group = false;
  };

  // Starts binary with args (argv[0] = binary). Throws std::runtime_error when fork fails; an
  // exec failure shows as exit code 127 with the reason in Output().
  ChildProcess(const std::string& binary, const std::vector<std::string>& args);
  ChildProcess(const std::string& binary, const std::vector<std::string>& args, Options options);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& name() const { return name_; }
  bool Running();
  void Signal(int signal_number);  // to the child (its group with own_process_group) while it runs

  // The exit code (128 + signal number when killed by a signal), or nothing while it still runs
  // at the timeout.
  std::optional<int> WaitExit(std::chrono::milliseconds timeout);
  // SIGTERM, wait up to grace for the exit, then SIGKILL. Returns the exit code (as WaitExit).
  int Stop(std::chrono::milliseconds grace = std::chrono::milliseconds(5000));

  // Everything the child wrote so far.
  std::string Output() const;
  // Waits until the output contains text; false at the timeout or once the child ended without it.
  bool WaitForOutput(const std::string& text, std::chrono::milliseconds timeout);
  // "--- name (pid N) ---\n<the last max_chars of Output()>" for failure messages.
  std::string Tail(std::size_t max_chars = 4000) const;

 private:
  int ExitCodeOf(int status) const;
  void Kill(int signal_number) const;  // to the child, or its group

  std::string name_;
  Options options_;
  bool owns_log_ = false;
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// Runs binary with args to its end (or the timeout); returns {exit code (-1 at the timeout), output}.
std::pair<int, std::string> RunToExit(const std::string& binary, const std::vector<std::string>& args,
                                      std::chrono::milliseconds timeout = std::chrono::seconds(15));

}  // namespace rslam::testing
