#include "tools/launch/process_supervisor.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace rslam::launch {

ProcessSupervisor::ProcessSupervisor(RestartPolicy policy) : policy_(policy) {}

ProcessSupervisor::~ProcessSupervisor() { StopAll(); }

void ProcessSupervisor::Event(const std::string& text) {
  if (on_event_) on_event_(text);
}

pid_t ProcessSupervisor::Spawn(const ProcessSpec& spec) {
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    const std::string key = entry.substr(0, entry.find('='));
    if (!spec.env.count(key)) env_strings.push_back(entry);
  }
  for (const auto& [k, v] : spec.env) env_strings.push_back(k + "=" + v);
  std::vector<char*> envp, argv;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string exe = spec.executable;
  argv.push_back(exe.data());
  std::vector<std::string> args = spec.args;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int log_fd = -1;
  if (!spec.log_file.empty()) {
    log_fd = ::open(spec.log_file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (log_fd < 0) throw std::runtime_error(spec.log_file + ": cannot open log: " + std::strerror(errno));
  }
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed: " + std::string(std::strerror(errno)));
  if (pid == 0) {
    // Child: default signal dispositions and an empty mask (the parent may block signals).
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    // Own process group: a Ctrl-C in the terminal reaches the supervisor, which stops children in order.
    setpgid(0, 0);
    if (log_fd >= 0) {
      dup2(log_fd, STDOUT_FILENO);
      dup2(log_fd, STDERR_FILENO);
    }
    execve(exe.c_str(), argv.data(), envp.data());
    std::fprintf(stderr, "cannot run %s: %s\n", exe.c_str(), std::strerror(errno));
    _exit(127);
  }
  if (log_fd >= 0) ::close(log_fd);
  return pid;
}

void ProcessSupervisor::Start(const ProcessSpec& spec) {
  if (::access(spec.executable.c_str(), X_OK) != 0)
    throw std::runtime_error(spec.executable + ": not found or not executable (build first?)");
  Child child;
  child.spec = spec;
  child.pid = Spawn(spec);
  Event("started " + spec.name + " (pid " + std::to_string(child.pid) + ")");
  children_.push_back(std::move(child));
}

void ProcessSupervisor::Poll() {
  const auto now = std::chrono::steady_clock::now();
  for (auto& c : children_) {
    if (c.pid > 0) {
      int status = 0;
      const pid_t r = ::waitpid(c.pid, &status, WNOHANG);
      if (r != c.pid) continue;
      c.pid = 0;
      c.last_exit = WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                      : "signal " + std::to_string(WTERMSIG(status));
      const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
      Event(c.spec.name + " ended (" + c.last_exit + ")");
      if (c.stopping || clean || !c.spec.restart) continue;
      if (c.restarts >= policy_.max_restarts) {
        c.gave_up = true;
        Event(c.spec.name + ": gave up after " + std::to_string(c.restarts) + " restarts");
        continue;
      }
      const double delay =
          std::min(policy_.backoff_max_s, policy_.backoff_initial_s * std::pow(2.0, c.restarts));
      c.restart_at = now + std::chrono::milliseconds(static_cast<int64_t>(delay * 1000));
    } else if (!c.stopping && !c.gave_up && c.restart_at != std::chrono::steady_clock::time_point{} &&
               now >= c.restart_at) {
      c.restart_at = {};
      ++c.restarts;
      c.pid = Spawn(c.spec);
      Event("restarted " + c.spec.name + " (pid " + std::to_string(c.pid) + ", restart " +
            std::to_string(c.restarts) + ")");
    }
  }
}

void ProcessSupervisor::Stop(const std::string& name, bool kill) {
  for (auto& c : children_) {
    if (c.spec.name != name) continue;
    c.stopping = true;
    if (c.pid > 0) ::kill(c.pid, kill ? SIGKILL : SIGTERM);
  }
}

void ProcessSupervisor::Signal(const std::string& name, int sig) {
  for (auto& c : children_)
    if (c.spec.name == name && c.pid > 0) ::kill(c.pid, sig);
}

bool ProcessSupervisor::StopAll(std::chrono::milliseconds grace) {
  // Stop in reverse start order: consumers first, so producers' last messages are not lost.
  for (auto it = children_.rbegin(); it != children_.rend(); ++it) {
    it->stopping = true;
    if (it->pid > 0) ::kill(it->pid, SIGTERM);
  }
  const auto deadline = std::chrono::steady_clock::now() + grace;
  bool clean = true;
  for (auto& c : children_) {
    while (c.pid > 0) {
      int status = 0;
      const pid_t r = ::waitpid(c.pid, &status, WNOHANG);
      if (r == c.pid || (r < 0 && errno == ECHILD)) {
        c.pid = 0;
        break;
      }
      if (std::chrono::steady_clock::now() >= deadline) {
        ::kill(c.pid, SIGKILL);
        ::waitpid(c.pid, &status, 0);
        Event(c.spec.name + " did not stop in time: killed");
        c.pid = 0;
        clean = false;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // waitpid has no timeout
    }
  }
  return clean;
}

std::vector<ProcessSupervisor::Status> ProcessSupervisor::Statuses() const {
  std::vector<Status> out;
  for (const auto& c : children_)
    out.push_back({c.spec.name, c.pid, c.restarts, c.pid > 0, c.gave_up, c.last_exit});
  return out;
}

bool ProcessSupervisor::AllRunning() const {
  return std::all_of(children_.begin(), children_.end(), [](const Child& c) { return c.pid > 0; });
}

}  // namespace rslam::launch
