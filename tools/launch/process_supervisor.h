#pragma once
// Starts a set of service processes, restarts one that crashes (with exponential backoff), and
// stops them all cleanly (SIGTERM, then SIGKILL after a grace period). Used by `rslam launch`
// and `rslam demo`.

#include <sys/types.h>

#include <chrono>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace rslam::launch {

struct ProcessSpec {
  std::string name;                  // e.g. "odometry"
  std::string executable;            // path to the binary
  std::vector<std::string> args;     // without argv[0]
  std::map<std::string, std::string> env;  // added to the parent's environment
  std::string log_file;              // stdout+stderr go here (appended); empty = inherit
  bool restart = true;               // restart when it exits abnormally
};

struct RestartPolicy {
  double backoff_initial_s = 0.5;
  double backoff_max_s = 10;
  int max_restarts = 5;              // per process; then it stays down and is reported
};

class ProcessSupervisor {
 public:
  explicit ProcessSupervisor(RestartPolicy policy = {});
  ~ProcessSupervisor();  // stops everything
  ProcessSupervisor(const ProcessSupervisor&) = delete;
  ProcessSupervisor& operator=(const ProcessSupervisor&) = delete;

  // Starts the process now. Throws std::runtime_error if it cannot be spawned.
  void Start(const ProcessSpec& spec);
  // Reaps exited children and restarts crashed ones whose backoff has passed. Call often.
  void Poll();
  // SIGTERM to all, wait up to grace, then SIGKILL. Returns true if all stopped in time. A grace
  // longer than the services' service.stop_timeout_s lets a service end a stop that runs long
  // itself, with its state saved, before it could be killed (rslam demo passes its config's).
  bool StopAll(std::chrono::milliseconds grace = std::chrono::milliseconds(8000));
  // SIGTERM (or SIGKILL) to one process by name, without restarting it.
  void Stop(const std::string& name, bool kill = false);
  // Sends a signal without changing the restart policy (a crash test kills with SIGKILL and
  // watches the supervisor restart it).
  void Signal(const std::string& name, int sig);

  struct Status {
    std::string name;
    pid_t pid = 0;          // 0 while down
    int restarts = 0;
    bool running = false;
    bool gave_up = false;
    std::string last_exit;  // "exit 0", "signal 9", ...
  };
  std::vector<Status> Statuses() const;
  bool AllRunning() const;
  // Called on every start/exit with a one-line description.
  void OnEvent(std::function<void(const std::string&)> callback) { on_event_ = std::move(callback); }

 private:
  struct Child {
    ProcessSpec spec;
    pid_t pid = 0;
    int restarts = 0;
    bool stopping = false;
    bool gave_up = false;
    std::string last_exit;
    std::chrono::steady_clock::time_point restart_at{};
  };
  pid_t Spawn(const ProcessSpec& spec);
  void Event(const std::string& text);

  const RestartPolicy policy_;
  std::vector<Child> children_;
  std::function<void(const std::string&)> on_event_;
};

}  // namespace rslam::launch
