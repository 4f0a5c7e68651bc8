#include "harness/run/dask_job_executor.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <stdexcept>

#include "build_info.hpp"
#include "harness/run/child_outcome_json.hpp"
#include "harness/run/interrupt.hpp"
#include "harness/run/job_status.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : fallback;
}

/// How long a blocking wait sleeps between looks at interrupted(), in milliseconds.
constexpr int kInterruptPollMs = 200;
/// How long the bridge may take to close its cluster before it is killed (its local workers
/// end with it), in seconds.
constexpr double kCloseSeconds = 60;

}  // namespace

std::string dask_python() {
  const fs::path venv = fs::path(BVHBENCH_SOURCE_DIR) / ".venv" / "bin" / "python";
  std::error_code ec;
  return env_or("BVHBENCH_PYTHON", fs::exists(venv, ec) ? venv.string() : "python3");
}

std::string dask_bridge_script() {
  return env_or("BVHBENCH_DASK_BRIDGE", (fs::path(BVHBENCH_SOURCE_DIR) / "harness" / "run" / "dask_bridge.py").string());
}

std::string comparison_group(const JobPlan& plan) {
  return plan.mesh.path + "|" + plan.queries.label() + "|" + plan.queries.file;
}

DaskJobExecutor::DaskJobExecutor(const DaskOptions& options) {
  worker_exe_ = options.worker_exe.empty() ? self_exe() : options.worker_exe;
  const std::string python = options.python.empty() ? dask_python() : options.python;
  const std::string bridge = options.bridge.empty() ? dask_bridge_script() : options.bridge;
  std::error_code ec;
  if (!fs::is_regular_file(bridge, ec))
    throw InputError(printable(bridge) + ": the Dask bridge script is not there (set BVHBENCH_DASK_BRIDGE)");
  std::vector<std::string> args = {python, bridge, "--workers", std::to_string(options.local_workers)};
  if (!options.scheduler.empty()) {
    args.push_back("--scheduler");
    args.push_back(options.scheduler);
  }

  int down[2], up[2];  // down: runner -> bridge (its stdin); up: bridge -> runner (its stdout)
  if (pipe2(down, O_CLOEXEC) != 0 || pipe2(up, O_CLOEXEC) != 0)
    throw std::runtime_error(std::string("pipe failed: ") + std::strerror(errno));
  // A bridge that died must not kill the runner when it writes: EPIPE is handled as its end.
  signal(SIGPIPE, SIG_IGN);
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid_ == 0) {
    // Its own process group: Ctrl-C reaches the runner, which stops the bridge in order
    // (interrupt.hpp). It dies with the runner (SIGTERM: its cluster's worker processes follow).
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);
    dup2(down[0], STDIN_FILENO);
    dup2(up[1], STDOUT_FILENO);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    const std::string msg = "bvhbench: cannot run the Python of the Dask bridge '" + python + "': " +
                            std::strerror(errno) + " (set BVHBENCH_PYTHON)\n";
    (void)!write(STDERR_FILENO, msg.data(), msg.size());
    _exit(127);
  }
  close(down[0]);
  close(up[1]);
  to_bridge_ = down[1];
  from_bridge_ = up[0];

  // The bridge says "ready" once it has a cluster, or why it has none.
  for (;;) {
    std::optional<json> m = read_message(-1);
    if (!m) {
      if (!eof_) continue;
      int st = 0;
      waitpid(pid_, &st, 0);
      pid_ = -1;
      throw InputError("the Dask bridge (" + python + " " + bridge + ") ended before it had a cluster" +
                       (WIFEXITED(st) ? " (exit code " + std::to_string(WEXITSTATUS(st)) + ")" : std::string()) +
                       "; see its message above");
    }
    const std::string event = m->value("event", "");
    if (event == "ready") {
      std::cerr << "suite: Dask scheduler " << m->value("scheduler", "?") << ", " << m->value("workers", 0)
                << " worker(s)" << (m->value("dashboard", "").empty() ? "" : ", dashboard " + m->value("dashboard", ""))
                << "\n";
      return;
    }
    if (event == "fatal") {
      const std::string why = m->value("message", "the Dask bridge failed");
      close(to_bridge_);
      to_bridge_ = -1;
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
      throw InputError(why);
    }
  }
}

DaskJobExecutor::~DaskJobExecutor() {
  if (pid_ < 0) return;
  try {
    send({{"op", tasks_.empty() ? "end" : "stop"}});
  } catch (...) {
  }
  if (to_bridge_ >= 0) close(to_bridge_);
  // The bridge closes its cluster and exits; its last messages are of no use now.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kCloseSeconds);
  while (!eof_ && std::chrono::steady_clock::now() < deadline) read_message(kInterruptPollMs);
  if (!eof_) {
    std::cerr << "suite: the Dask bridge did not close its cluster in " << kCloseSeconds << " s; killed\n";
    kill(-pid_, SIGKILL);
  }
  close(from_bridge_);
  waitpid(pid_, nullptr, 0);
}

std::size_t DaskJobExecutor::slots() const { return std::numeric_limits<std::size_t>::max(); }

void DaskJobExecutor::send(const json& message) {
  if (to_bridge_ < 0) return;
  const std::string line = message.dump() + "\n";
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = write(to_bridge_, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      close(to_bridge_);  // the bridge is gone: its end is read from its pipe
      to_bridge_ = -1;
      return;
    }
    done += std::size_t(n);
  }
}

void DaskJobExecutor::submit(JobTask task) {
  const JobSpec& spec = task.spec;
  json paths = json::array({spec.mesh_path, spec.queries_path});
  if (!spec.truth_path.empty()) paths.push_back(spec.truth_path);
  send({{"op", "submit"},
        {"index", task.index},
        {"id", task.plan.id},
        {"group", comparison_group(task.plan)},
        {"exe", worker_exe_},
        {"args", run_arguments(spec)},
        {"inputs", paths},
        {"timeout_s", task.limits.timeout_s},
        {"memory_limit_mb", task.limits.memory_limit_mb},
        {"log_path", task.log_path},
        {"result_path", task.child_result_path}});
  tasks_.emplace(task.index, std::move(task));
}

std::optional<json> DaskJobExecutor::read_message(int wait_ms) {
  for (;;) {
    const std::size_t nl = buffer_.find('\n');
    if (nl != std::string::npos) {
      const std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      try {
        json m = json::parse(line);
        if (m.is_object()) return m;
      } catch (const json::exception&) {
      }
      if (!line.empty()) std::cerr << "dask bridge: " << printable(line) << "\n";  // not ours: show it
      continue;
    }
    if (eof_) return std::nullopt;
    pollfd p{from_bridge_, POLLIN, 0};
    const int r = poll(&p, 1, wait_ms);
    if (r == 0 || (r < 0 && errno == EINTR)) return std::nullopt;
    char chunk[65536];
    const ssize_t n = read(from_bridge_, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) return std::nullopt;
    if (n <= 0) {
      eof_ = true;
      return std::nullopt;
    }
    buffer_.append(chunk, std::size_t(n));
  }
}

std::optional<JobFinished> DaskJobExecutor::finish(const json& m) {
  const std::string event = m.value("event", "");
  if (event != "done" && event != "lost" && event != "stopped") {
    if (event == "note") std::cerr << "suite: " << m.value("message", "") << "\n";
    return std::nullopt;
  }
  auto it = tasks_.find(m.value("index", std::numeric_limits<std::size_t>::max()));
  if (it == tasks_.end()) return std::nullopt;
  JobFinished f{std::move(it->second), json(), true};
  tasks_.erase(it);
  const JobTask& t = f.task;
  if (event == "stopped") {
    f.kept = false;
    return f;
  }
  const ChildOutcome outcome = child_outcome_from_json(m.value("outcome", json::object()));
  bool own_result = false;
  if (event == "lost") {
    f.result = job_failure_row(t.spec, t.plan, status::crash, m.value("message", "its Dask worker was lost"));
  } else if (m.contains("refused")) {
    // The worker could not start the job (an input it cannot read, no bvhbench there).
    f.result = job_failure_row(t.spec, t.plan, m.value("refused_status", std::string(status::error)),
                               m.value("refused", ""));
  } else if (read_result_file(t.child_result_path, &f.result)) {
    own_result = true;
  } else {
    f.result = status_row(t.spec, t.plan, outcome, t.limits.timeout_s);
  }
  // A row made here names the worker's host, where the job ran, not the runner's.
  if (!own_result && m.contains("host")) f.result["context"]["host"] = m.value("host", "");
  f.result["executor"] = {{"name", "dask"}, {"worker", m.value("worker", "")}, {"attempts", m.value("attempts", 1)}};
  f.result["elapsed_seconds"] = outcome.seconds;
  return f;
}

void DaskJobExecutor::stop_on_interrupt() {
  if (stop_sent_ || !interrupted()) return;
  stop_sent_ = true;
  send({{"op", "stop"}});
}

std::optional<JobFinished> DaskJobExecutor::collect() {
  while (!tasks_.empty()) {
    stop_on_interrupt();
    std::optional<json> m = read_message(kInterruptPollMs);
    if (m) {
      if (std::optional<JobFinished> f = finish(*m)) return f;
      continue;
    }
    if (eof_ && stop_sent_) {
      // Stopped, and gone before it said so of every job: the rest are unfinished all the same.
      JobFinished f{std::move(tasks_.begin()->second), json(), false};
      tasks_.erase(tasks_.begin());
      return f;
    }
    if (eof_) {
      int st = 0;
      waitpid(pid_, &st, 0);
      pid_ = -1;
      throw std::runtime_error("the Dask bridge ended with " + std::to_string(tasks_.size()) +
                               " job(s) not done; run the suite again with --resume to finish it");
    }
  }
  return std::nullopt;
}

std::optional<JobFinished> DaskJobExecutor::collect_ready() {
  stop_on_interrupt();
  while (std::optional<json> m = read_message(0))
    if (std::optional<JobFinished> f = finish(*m)) return f;
  return std::nullopt;
}

}  // namespace bvhbench
