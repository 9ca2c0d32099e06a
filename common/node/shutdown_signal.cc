#include "common/node/shutdown_signal.h"

#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <ctime>

namespace rslam {
namespace {

sigset_t ShutdownSet() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR1);  // RequestShutdown
  return set;
}

}  // namespace

void BlockShutdownSignals() {
  const sigset_t set = ShutdownSet();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

int WaitForShutdown(std::chrono::milliseconds period, void (*on_tick)(void*), void* arg) {
  const sigset_t set = ShutdownSet();
  while (true) {
    int sig = -1;
    if (period.count() > 0) {
      timespec ts{static_cast<time_t>(period.count() / 1000), static_cast<long>((period.count() % 1000) * 1000000)};
      sig = sigtimedwait(&set, nullptr, &ts);
      if (sig < 0) {
        if (errno == EAGAIN && on_tick != nullptr) on_tick(arg);
        continue;
      }
    } else if (sigwait(&set, &sig) != 0) {
      continue;
    }
    return sig == SIGUSR1 ? 0 : sig;
  }
}

void RequestShutdown() { kill(getpid(), SIGUSR1); }

ExitDeadline::ExitDeadline(std::chrono::milliseconds timeout, std::string what)
    : thread_([this, timeout, what = std::move(what)] {
        std::unique_lock lock(mutex_);
        if (cv_.wait_for(lock, timeout, [this] { return done_; })) return;
        spdlog::warn("{} did not finish within {} ms: exiting without it", what, timeout.count());
        spdlog::default_logger()->flush();
        std::_Exit(0);
      }) {}

ExitDeadline::~ExitDeadline() {
  {
    std::lock_guard lock(mutex_);
    done_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

}  // namespace rslam
