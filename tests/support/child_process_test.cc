#include "tests/support/child_process.h"

#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace rslam::testing {
namespace {

using namespace std::chrono_literals;

// True while process `pid` runs (not gone, not a zombie waiting for its new parent to reap it).
bool Alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string pid_field, name, state;
  return stat >> pid_field >> name >> state && state != "Z";
}

// A shell that starts `sleep 60` in the background, writes its pid to a file and waits.
pid_t StartShellWithSleep(const ScratchFolder& dir, bool own_process_group, std::unique_ptr<ChildProcess>& shell) {
  ChildProcess::Options options;
  options.own_process_group = own_process_group;
  const std::string script =
      "sleep 60 & echo $! > " + dir / "pid.tmp" + "; mv " + dir / "pid.tmp" + " " + dir / "pid" + "; wait";
  shell = std::make_unique<ChildProcess>("/bin/sh", std::vector<std::string>{"-c", script}, options);
  pid_t pid = 0;
  EXPECT_TRUE(WaitFor([&] { return bool(std::ifstream(dir / "pid") >> pid); }, 10s)) << shell->Output();
  return pid;
}

TEST(ChildProcessTest, OwnProcessGroupEndsWhatTheChildStarted) {
  ScratchFolder dir;
  std::unique_ptr<ChildProcess> shell;
  const pid_t sleep_pid = StartShellWithSleep(dir, /*own_process_group=*/true, shell);
  ASSERT_GT(sleep_pid, 0);
  ASSERT_TRUE(Alive(sleep_pid));
  shell->Stop(2s);
  EXPECT_TRUE(WaitFor([&] { return !Alive(sleep_pid); }, 5s)) << "the shell's sleep outlived it";
}

TEST(ChildProcessTest, WithoutItOnlyTheChildIsSignalled) {
  ScratchFolder dir;
  std::unique_ptr<ChildProcess> shell;
  const pid_t sleep_pid = StartShellWithSleep(dir, /*own_process_group=*/false, shell);
  ASSERT_GT(sleep_pid, 0);
  shell->Stop(2s);
  EXPECT_TRUE(Alive(sleep_pid)) << "the sleep was signalled although the group was not asked for";
  ::kill(sleep_pid, SIGKILL);
}

}  // namespace
}  // namespace rslam::testing
