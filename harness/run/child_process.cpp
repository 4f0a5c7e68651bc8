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

std::string tail_of_file(const std::string& path, std::size_t max_bytes = 2000) {
  std::ifstream f(path, std::ios::binary);
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (s.size() > max_bytes) s = "..." + s.substr(s.size() - max_bytes);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

}  // namespace

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

ChildOutcome run_child(const std::vector<std::string>& args, const ChildLimits& limits,
                       const std::string& log_path) {
  ChildOutcome out;
  auto t0 = std::chrono::steady_clock::now();
  const pid_t parent = getpid();
  pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
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
  setpgid(pid, pid);
  g_child = pid;
  int st = 0;
  for (;;) {
    pid_t w = waitpid(pid, &st, WNOHANG);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) break;
    double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (el > limits.timeout_s && !out.timed_out) {
      out.timed_out = true;
      kill(-pid, SIGKILL);
    }
    if (limits.outlive_no_longer_than > 0 && getppid() != limits.outlive_no_longer_than) {
      // Whoever started us is gone (a Dask worker killed mid-job): nobody will read the result,
      // so the job must not run on to its time limit.
      kill(-pid, SIGKILL);
      waitpid(pid, &st, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(el < 2 ? 5 : 50));
  }
  g_child = 0;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (WIFEXITED(st)) {
    out.exited = true;
    out.exit_code = WEXITSTATUS(st);
  } else if (WIFSIGNALED(st)) {
    out.signal = WTERMSIG(st);
  }
  out.stderr_tail = tail_of_file(log_path);
  return out;
}

}  // namespace bvhbench
