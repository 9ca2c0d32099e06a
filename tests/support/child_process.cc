#include "tests/support/child_process.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace rslam::testing {

bool WaitFor(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

bool WaitForNewMatches(const std::vector<std::function<int()>>& counts, std::chrono::milliseconds timeout) {
  std::vector<int> lowest;
  for (const auto& count : counts) lowest.push_back(count());
  return WaitFor(
      [&] {
        bool all = true;
        for (size_t i = 0; i < counts.size(); ++i) {
          const int now = counts[i]();
          lowest[i] = std::min(lowest[i], now);
          all = all && now > lowest[i];
        }
        return all;
      },
      timeout);
}

ScratchFolder::ScratchFolder(const std::string& prefix) {
  std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed: " + std::string(std::strerror(errno)));
  path_ = pattern;
}

ScratchFolder::~ScratchFolder() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::filesystem::path ScratchFolderForTest() {
  static const ScratchFolder process_folder("rslam-test");
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "_" + info->name();
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const std::filesystem::path dir = process_folder.path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

namespace {

std::string TemporaryLogPath(const std::string& name) {
  static std::atomic<int> counter{0};
  return (std::filesystem::temp_directory_path() /
          ("rslam-child-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" + name + ".log"))
      .string();
}

}  // namespace

ChildProcess::ChildProcess(const std::string& binary, const std::vector<std::string>& args)
    : ChildProcess(binary, args, Options{}) {}

ChildProcess::ChildProcess(const std::string& binary, const std::vector<std::string>& args, Options options)
    : name_(std::filesystem::path(binary).filename().string()), options_(std::move(options)) {
  if (options_.log_file.empty()) {
    options_.log_file = TemporaryLogPath(name_);
    owns_log_ = true;
  }
  // Everything the child needs is prepared before fork: after it, only async-signal-safe calls.
  std::vector<std::string> argv_storage{binary};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::map<std::string, std::string> environment;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    const auto eq = entry.find('=');
    if (eq != std::string::npos) environment[entry.substr(0, eq)] = entry.substr(eq + 1);
  }
  for (const auto& [key, value] : options_.environment) environment[key] = value;
  std::vector<std::string> env_storage;
  for (const auto& [key, value] : environment) env_storage.push_back(key + "=" + value);
  std::vector<char*> envp;
  for (auto& e : env_storage) envp.push_back(e.data());
  envp.push_back(nullptr);
  const int log_fd = ::open(options_.log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot open " + options_.log_file + ": " + std::strerror(errno));

  pid_ = ::fork();
  if (pid_ < 0) {
    ::close(log_fd);
    throw std::runtime_error("fork failed: " + std::string(std::strerror(errno)));
  }
  if (pid_ == 0) {
    // The test may block signals for its own threads; the child starts with none blocked.
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    if (options_.own_process_group) ::setpgid(0, 0);
    ::dup2(log_fd, STDOUT_FILENO);
    ::dup2(log_fd, STDERR_FILENO);
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
    ::execve(binary.c_str(), argv.data(), envp.data());
    const char* reason = std::strerror(errno);
    (void)!::write(STDERR_FILENO, "exec failed: ", 13);
    (void)!::write(STDERR_FILENO, reason, std::strlen(reason));
    (void)!::write(STDERR_FILENO, "\n", 1);
    ::_exit(127);
  }
  // Also from this side, so a signal sent right away already reaches the group.
  if (options_.own_process_group) ::setpgid(pid_, pid_);
  ::close(log_fd);
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !status_) Stop(options_.stop_grace);
  if (owns_log_) {
    std::error_code ignored;
    std::filesystem::remove(options_.log_file, ignored);
  }
}

bool ChildProcess::Running() {
  if (status_) return false;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    status_ = status;
    return false;
  }
  return true;
}

void ChildProcess::Kill(int signal_number) const { ::kill(options_.own_process_group ? -pid_ : pid_, signal_number); }

void ChildProcess::Signal(int signal_number) {
  if (Running()) Kill(signal_number);
}

int ChildProcess::ExitCodeOf(int status) const {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

std::optional<int> ChildProcess::WaitExit(std::chrono::milliseconds timeout) {
  if (!WaitFor([this] { return !Running(); }, timeout)) return std::nullopt;
  return ExitCodeOf(*status_);
}

int ChildProcess::Stop(std::chrono::milliseconds grace) {
  Signal(SIGTERM);
  if (const auto code = WaitExit(grace)) return *code;
  Kill(SIGKILL);
  int status = 0;
  if (::waitpid(pid_, &status, 0) == pid_) status_ = status;
  return status_ ? ExitCodeOf(*status_) : -1;
}

std::string ChildProcess::Output() const {
  std::ifstream in(options_.log_file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool ChildProcess::WaitForOutput(const std::string& text, std::chrono::milliseconds timeout) {
  bool found = false;
  WaitFor([&] { return (found = Output().find(text) != std::string::npos) || !Running(); }, timeout);
  return found || Output().find(text) != std::string::npos;
}

std::string ChildProcess::Tail(std::size_t max_chars) const {
  std::string text = Output();
  if (text.size() > max_chars) text = "..." + text.substr(text.size() - max_chars);
  return "--- " + name_ + " (pid " + std::to_string(pid_) + ") ---\n" + text + "\n";
}

std::pair<int, std::string> RunToExit(const std::string& binary, const std::vector<std::string>& args,
                                      std::chrono::milliseconds timeout) {
  ChildProcess process(binary, args);
  const std::optional<int> code = process.WaitExit(timeout);
  return {code.value_or(-1), process.Output()};
}

}  // namespace rslam::testing
