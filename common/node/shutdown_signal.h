#pragma once
// SIGINT and SIGTERM end a service cleanly: main blocks them before any thread starts and
// waits for one; every node then saves its state in its destructor.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace rslam {

// Blocks SIGINT/SIGTERM in the calling thread and every thread it creates afterwards.
void BlockShutdownSignals();
// Waits for SIGINT or SIGTERM (or RequestShutdown); returns the signal number (0 if requested).
// With a period, calls on_tick every period while waiting.
int WaitForShutdown(std::chrono::milliseconds period = std::chrono::milliseconds(0), void (*on_tick)(void*) = nullptr,
                    void* arg = nullptr);
// Makes WaitForShutdown return (e.g. when a node finishes its input).
void RequestShutdown();

// Ends the process with exit code 0 if it is still alive `timeout` after construction, unless
// destroyed first. main arms one when a stop begins: Fast DDS 2.9 can deadlock deleting its
// entities while the peers leave at the same moment (a timer's removal waits for the event
// thread, which waits for a lock the removal holds; eProsima/Fast-DDS#6193 and #6502). The node
// saves its state first and state files are renamed into place whole, so the process logs a
// warning and exits rather than waiting for its launcher to kill it.
class ExitDeadline {
 public:
  ExitDeadline(std::chrono::milliseconds timeout, std::string what);
  ~ExitDeadline();
  ExitDeadline(const ExitDeadline&) = delete;
  ExitDeadline& operator=(const ExitDeadline&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace rslam
