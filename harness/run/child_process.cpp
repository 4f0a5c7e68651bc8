#include "harness/run/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <thread>

namespace bvhbench {

namespace {

// The child being waited for, for kill_running_child() from a signal handler.
volatile pid_t g_child = 0;

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// In the forked child: its process group, death with the parent, limits, log; then exec.
[[noreturn]] void exec_child(const std::vector<std::string>& args, const ChildLimits& limits,
                             const std::string& log_path, pid_t parent) {
  setpgid(0, 0);
  // The job dies with the runner (a SIGKILLed runner must not leave jobs writing results).
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(127);
  if (limits.memory_limit_mb > 0) {
    rlimit rl;
    // A limit beyond what rlim_t holds is no limit (converting it would be undefined).
    const double bytes = limits.memory_limit_mb * 1024.0 * 1024.0;
    rl.rlim_cur = rl.rlim_max = bytes < 0x1p63 ? rlim_t(bytes) : RLIM_INFINITY;
    setrlimit(RLIMIT_AS, &rl);
  }
  rlimit core{0, 0};
  setrlimit(RLIMIT_CORE, &core);
  int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    dup2(fd, STDERR_FILENO);
    dup2(fd, STDOUT_FILENO);
    close(fd);
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  execv(argv[0], argv.data());
  _exit(127);
}

}  // namespace

std::string log_tail(const std::string& path, std::size_t max_bytes) {
  std::ifstream f(path, std::ios::binary);
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (s.size() > max_bytes) s = "..." + s.substr(s.size() - max_bytes);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

void kill_running_child() noexcept {
  const pid_t child = g_child;
  if (child > 0) kill(-child, SIGKILL);
}

std::string self_exe() {
  char buf[4096];
  ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) throw std::runtime_error("cannot find /proc/self/exe");
  return std::string(buf, std::size_t(n));
}

ChildRun::ChildRun(const std::vector<std::string>& args, const ChildLimits& limits, const std::string& log_path)
    : limits_(limits), log_path_(log_path) {
  started_ = clock_from_ = now_seconds();
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid_ == 0) exec_child(args, limits, log_path, parent);
  setpgid(pid_, pid_);
  g_child = pid_;
}

ChildRun::~ChildRun() {
  if (ended_ || pid_ <= 0) return;
  kill(-pid_, SIGKILL);
  int st = 0;
  waitpid(pid_, &st, 0);
  if (g_child == pid_) g_child = 0;
}

void ChildRun::restart_clock() { clock_from_ = now_seconds(); }

double ChildRun::seconds() const { return now_seconds() - started_; }

bool ChildRun::poll() {
  if (ended_) return true;
  int st = 0;
  const pid_t w = waitpid(pid_, &st, WNOHANG);
  if (w == pid_ || (w < 0 && errno != EINTR)) {
    reap(st);
    return true;
  }
  if (now_seconds() - clock_from_ > limits_.timeout_s && !out_.timed_out) {
    out_.timed_out = true;
    kill(-pid_, SIGKILL);
  }
  if (limits_.outlive_no_longer_than > 0 && getppid() != limits_.outlive_no_longer_than) {
    // Whoever started us is gone (a Dask worker killed mid-job): nobody will read the result,
    // so the job must not run on to its time limit.
    kill(-pid_, SIGKILL);
    waitpid(pid_, &st, 0);
    reap(st);
    return true;
  }
  return false;
}

void ChildRun::reap(int st) {
  ended_ = true;
  if (g_child == pid_) g_child = 0;
  out_.seconds = seconds();
  if (WIFEXITED(st)) {
    out_.exited = true;
    out_.exit_code = WEXITSTATUS(st);
  } else if (WIFSIGNALED(st)) {
    out_.signal = WTERMSIG(st);
  }
  out_.stderr_tail = log_tail(log_path_);
}

ChildOutcome run_child(const std::vector<std::string>& args, const ChildLimits& limits,
                       const std::string& log_path) {
  ChildRun child(args, limits, log_path);
  while (!child.poll())
    std::this_thread::sleep_for(std::chrono::milliseconds(child.seconds() < 2 ? 5 : 50));
  return child.outcome();
}

}  // namespace bvhbench
