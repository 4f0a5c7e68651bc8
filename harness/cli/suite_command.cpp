// `bvhbench suite SUITE.yml --out results/NAME`: every job of a suite in its own child process
// (time and address-space limits), the query sets and oracle files each made once, results
// written atomically, `--resume`. The suite file itself is read by run/suite.hpp.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>

#include "harness/cli/commands.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/suite.hpp"
#include "harness/run/summary_csv.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_path.hpp"
#include "harness/util/progress.hpp"
#include "harness/util/sha256.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// Child processes
// ---------------------------------------------------------------------------------------------
namespace {

volatile sig_atomic_t g_interrupted = 0;
volatile pid_t g_child = 0;

void on_interrupt(int) {
  g_interrupted = 1;
  if (g_child > 0) kill(-g_child, SIGKILL);
}

struct ChildOutcome {
  bool exited = false;
  int exit_code = 0;
  int signal = 0;
  bool timed_out = false;
  double seconds = 0;
  std::string stderr_tail;
};

std::string self_exe() {
  char buf[4096];
  ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) throw std::runtime_error("cannot find /proc/self/exe");
  return std::string(buf, std::size_t(n));
}

std::string tail_of_file(const std::string& path, std::size_t max_bytes = 2000) {
  std::ifstream f(path, std::ios::binary);
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (s.size() > max_bytes) s = "..." + s.substr(s.size() - max_bytes);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

/// Runs argv in a child with an address-space limit and a wall-clock limit. The child gets its
/// own process group so that a timeout or an interrupt kills whatever it started, too.
ChildOutcome run_child(const std::vector<std::string>& args, double timeout_s, double memory_limit_mb,
                       const std::string& stderr_path) {
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
    if (memory_limit_mb > 0) {
      rlimit rl;
      // A limit beyond what rlim_t holds is no limit (converting it would be undefined).
      const double bytes = memory_limit_mb * 1024.0 * 1024.0;
      rl.rlim_cur = rl.rlim_max = bytes < 0x1p63 ? rlim_t(bytes) : RLIM_INFINITY;
      setrlimit(RLIMIT_AS, &rl);
    }
    rlimit core{0, 0};
    setrlimit(RLIMIT_CORE, &core);
    int fd = open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
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
    if (el > timeout_s && !out.timed_out) {
      out.timed_out = true;
      kill(-pid, SIGKILL);
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
  out.stderr_tail = tail_of_file(stderr_path);
  return out;
}

/// What a result says of its query set when the job left none: the plan. A points file has no
/// n or seed until it is read.
void set_planned_queries(json& r, const QueryPlan& q, bool with_seed) {
  r["job"]["queries"]["kind"] = q.kind;
  if (!q.file.empty()) {
    r["job"]["queries"]["path"] = printable(q.file);
    return;
  }
  r["job"]["queries"]["n"] = q.n;
  if (with_seed) r["job"]["queries"]["seed"] = q.seed;
}

/// Status row for a job whose child left no result file.
json status_row(const JobSpec& spec, const JobPlan& plan, const ChildOutcome& o, double timeout_s) {
  std::string code, msg;
  bool bad_alloc = o.stderr_tail.find("bad_alloc") != std::string::npos ||
                   o.stderr_tail.find("out of memory") != std::string::npos ||
                   o.stderr_tail.find("Cannot allocate memory") != std::string::npos;
  if (o.timed_out) {
    code = status::timeout;
    msg = "killed after the time limit of " + format_seconds(timeout_s);
  } else if (o.signal == SIGKILL || bad_alloc) {
    code = status::oom;
    msg = o.signal == SIGKILL ? "killed (SIGKILL: out of memory?)" : "out of memory";
  } else if (o.signal) {
    code = status::crash;
    msg = std::string("killed by signal ") + std::to_string(o.signal) + " (" + strsignal(o.signal) + ")";
  } else {
    code = o.exit_code == 2 ? status::rejected_input : status::error;
    msg = "exit code " + std::to_string(o.exit_code) + " without a result";
  }
  if (!o.stderr_tail.empty()) {
    std::string t = o.stderr_tail;
    if (t.size() > 500) t = "..." + t.substr(t.size() - 500);
    msg += "; stderr: " + t;
  }
  json r = make_result(spec, code, msg);
  r["job"]["id"] = plan.id;
  r["job"]["mesh"]["name"] = plan.mesh.name;
  set_planned_queries(r, plan.queries, true);
  r["elapsed_seconds"] = o.seconds;
  return r;
}

bool read_json(const std::string& path, json* out) {
  std::ifstream f(path);
  if (!f) return false;
  try {
    *out = json::parse(f);
    return out->is_object() && out->contains("status");
  } catch (...) {
    return false;
  }
}

std::string short_result(const json& r) {
  std::string s = r.value("status", "?");
  json q = json_at(r, {"queries", "throughput_qps", "median"});
  if (s == "ok" && q.is_number()) {
    char buf[64];
    std::snprintf(buf, sizeof buf, " %.3g q/s", q.get<double>());
    s += buf;
  } else if (s != "ok") {
    std::string m = r.value("message", "");
    if (m.size() > 80) m = m.substr(0, 77) + "...";
    if (!m.empty()) s += " (" + m + ")";
  }
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// `bvhbench suite SUITE.yml --out results/NAME [--resume] [--filter REGEX]`
// ---------------------------------------------------------------------------------------------
void add_suite_command(CLI::App& app) {
  struct Opts {
    std::string file, out, filter, data_dir;
    bool resume = false, list = false, no_truth = false;
    double timeout_s = -1, memory_limit_mb = -1;
    int repeat = -1;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand("suite", "Run a YAML matrix of jobs, each in its own child process");
  cmd->add_option("suite", o->file,
                  "Suite file (suites/*.yml): meshes x query sets (generated, or points files given as "
                  "{file: PATH}) x queries x methods; format in suites/README.md")
      ->required();
  cmd->add_option("--out", o->out, "Result folder (results/NAME)")->required();
  cmd->add_flag("--resume", o->resume, "Skip jobs whose result is already written");
  cmd->add_option("--filter", o->filter, "Run only jobs whose id matches this regex");
  cmd->add_flag("--list", o->list, "Print the expanded job ids and exit");
  cmd->add_option("--timeout", o->timeout_s, "Per-job time limit in seconds (overrides the suite)");
  cmd->add_option("--memory-limit", o->memory_limit_mb, "Per-job address-space limit in MiB (overrides the suite)");
  cmd->add_option("--repeat", o->repeat, "Timed passes per job (overrides the suite)");
  cmd->add_flag("--no-truth", o->no_truth, "Do not compute or attach oracle answers");
  cmd->add_option("--data", o->data_dir, "Cache for query sets and oracle files (default: OUT/data)");
  cmd->callback([o] {
    SuiteConfig cfg = load_suite(o->file);
    if (o->timeout_s > 0) cfg.timeout_s = o->timeout_s;
    if (o->memory_limit_mb >= 0) cfg.memory_limit_mb = o->memory_limit_mb;
    if (o->repeat > 0) cfg.repeat = o->repeat;
    if (o->no_truth) cfg.truth = false;
    std::vector<JobPlan> jobs;
    std::regex re;
    try {
      re = std::regex(o->filter.empty() ? ".*" : o->filter);
    } catch (const std::regex_error& e) {
      throw InputError("--filter '" + o->filter + "': bad regex: " + e.what());
    }
    for (auto& j : cfg.jobs)
      if (std::regex_search(j.id, re)) jobs.push_back(j);
    if (o->list) {
      for (auto& j : jobs) std::cout << j.id << "\n";
      return;
    }
    const fs::path out = o->out;
    const fs::path runs = out / "runs", logs = out / "logs";
    const fs::path data = o->data_dir.empty() ? out / "data" : fs::path(o->data_dir);
    fs::create_directories(runs);
    fs::create_directories(logs);
    fs::create_directories(data / "queries");
    fs::create_directories(data / "truth");
    {
      std::ifstream src(o->file);
      std::ofstream dst(out / "suite.yml");
      dst << src.rdbuf();
    }
    const std::string exe = self_exe();

    struct sigaction sa {};
    sa.sa_handler = on_interrupt;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);

    // Query sets and oracle files, each made once (in a child: a bad mesh must not end the suite).
    std::map<std::string, std::pair<std::string, std::string>> qsets;  // key -> (npy, error)
    std::map<std::string, std::string> truths;                        // npy+mesh -> truth ("" = none)
    bool truth_unavailable = false;
    auto prepare_queries = [&](const JobPlan& j) -> std::pair<std::string, std::string> {
      if (!j.queries.file.empty()) {
        // Read by each job (a malformed file is its rejected_input); here only what would stop
        // the oracle from hashing it.
        std::error_code ec;
        if (!fs::is_regular_file(j.queries.file, ec)) return {"", j.queries.file + ": points file not found"};
        if (!std::ifstream(j.queries.file)) return {"", j.queries.file + ": points file cannot be read"};
        return {j.queries.file, ""};
      }
      std::string key = j.mesh.path + "|" + j.queries.label();
      auto it = qsets.find(key);
      if (it != qsets.end()) return it->second;
      std::string npy = (data / "queries" / (file_safe(j.mesh.name) + "__" + j.queries.label() + ".npy")).string();
      std::string err;
      json meta;
      bool fresh = false;
      if (fs::exists(npy) && fs::exists(sidecar_path(npy))) {
        // Reuse only if it was made from this very mesh file.
        std::ifstream f(sidecar_path(npy));
        try {
          meta = json::parse(f);
          fresh = meta.value("mesh_path", "") == j.mesh.path && fs::exists(j.mesh.path) &&
                  meta.value("mesh_sha256", "") == sha256_file(j.mesh.path);
        } catch (...) {
          fresh = false;
        }
      }
      if (!fresh) {
        std::vector<std::string> args = {exe, "--quiet", "queries", "--mesh", j.mesh.path, "--kind", j.queries.kind,
                                         "--n", std::to_string(j.queries.n), "--seed", std::to_string(j.queries.seed),
                                         "--out", npy};
        for (auto& [k, v] : j.queries.params) args.push_back("--param=" + k + "=" + format_number(v));
        std::cerr << "suite: making query set " << fs::path(npy).filename().string() << "\n";
        auto r = run_child(args, cfg.timeout_s, cfg.memory_limit_mb, (logs / ("queries__" + file_safe(j.mesh.name) + "__" + j.queries.label() + ".log")).string());
        if (!(r.exited && r.exit_code == 0)) {
          err = r.stderr_tail.empty() ? "query generation failed" : r.stderr_tail;
          npy.clear();
        }
      }
      return qsets[key] = {npy, err};
    };
    auto prepare_truth = [&](const JobPlan& j, const std::string& npy) -> std::string {
      if (!cfg.truth || truth_unavailable || npy.empty()) return "";
      std::string key = j.mesh.path + "|" + npy;
      auto it = truths.find(key);
      if (it != truths.end()) return it->second;
      std::string msha = sha256_file(j.mesh.path), qsha = sha256_file(npy);
      std::string path = (data / "truth" / (msha.substr(0, 16) + "_" + qsha.substr(0, 16) + ".npz")).string();
      if (!fs::exists(path)) {
        std::cerr << "suite: computing oracle for " << j.mesh.name << " / " << j.queries.label() << "\n";
        auto r = run_child({exe, "--quiet", "truth", "--mesh", j.mesh.path, "--queries", npy, "--out", path},
                           std::max(cfg.timeout_s, 1800.0), cfg.memory_limit_mb,
                           (logs / ("truth__" + file_safe(j.mesh.name) + "__" + j.queries.label() + ".log")).string());
        if (!(r.exited && r.exit_code == 0)) {
          if (r.stderr_tail.find("not implemented") != std::string::npos) truth_unavailable = true;
          std::cerr << "suite: no oracle for " << j.mesh.name << ": " << r.stderr_tail << "\n";
          path.clear();
        }
      }
      return truths[key] = path;
    };

    std::vector<json> done;
    std::size_t finished = 0, skipped = 0;
    // summary.csv covers every job of the suite that has a result in this folder, in suite order,
    // not only the ones this invocation ran (--filter, --resume).
    std::map<std::string, json> summary_rows;
    for (auto& j : cfg.jobs) {
      json r;
      if (read_json((runs / (j.id + ".json")).string(), &r)) summary_rows[j.id] = r;
    }
    auto write_summary = [&] {
      std::vector<json> rows;
      for (auto& j : cfg.jobs) {
        auto it = summary_rows.find(j.id);
        if (it != summary_rows.end()) rows.push_back(it->second);
      }
      write_summary_csv((out / "summary.csv").string(), rows);
    };
    // Jobs this invocation will actually run (for the time-left estimate): --resume skips the rest.
    std::size_t to_run = jobs.size();
    if (o->resume)
      for (auto& j : jobs)
        if (fs::exists(runs / (j.id + ".json")) || fs::exists(runs / (j.id + ".json.child"))) --to_run;
    double spent = 0;
    auto t_start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < jobs.size() && !g_interrupted; ++i) {
      const JobPlan& j = jobs[i];
      const std::string result_path = (runs / (j.id + ".json")).string();
      const std::string child_path = (runs / (j.id + ".json.child")).string();
      json existing;
      if (o->resume && read_json(result_path, &existing)) {
        done.push_back(existing);
        ++skipped;
        continue;
      }
      if (o->resume && read_json(child_path, &existing)) {
        // The job finished but the runner was killed before recording it: adopt the result.
        existing["job"]["id"] = j.id;
        existing["job"]["mesh"]["name"] = j.mesh.name;
        existing["job"]["suite"] = cfg.name;
        write_json_atomic(result_path, existing);
        std::remove(child_path.c_str());
        summary_rows[j.id] = existing;
        done.push_back(existing);
        ++skipped;
        continue;
      }
      auto tj = std::chrono::steady_clock::now();
      JobSpec spec;
      spec.mesh_path = j.mesh.path;
      spec.method = j.method;
      spec.query_type = j.query;
      spec.repeat = cfg.repeat;
      json result;
      auto [npy, qerr] = prepare_queries(j);
      if (g_interrupted) break;  // the query set was cut short: not this job's failure
      spec.queries_path = npy;
      if (npy.empty()) {
        result = make_result(spec, qerr.find("exit code") == std::string::npos ? status::rejected_input : status::error,
                             (j.queries.file.empty() ? "query set could not be made: " : "query set refused: ") + qerr);
        result["job"]["id"] = j.id;
        result["job"]["mesh"]["name"] = j.mesh.name;
        set_planned_queries(result, j.queries, false);
      } else {
        spec.truth_path = prepare_truth(j, npy);
        if (g_interrupted) break;
        std::vector<std::string> args = {exe, "--quiet", "run", "--mesh", spec.mesh_path, "--method", spec.method.text,
                                         "--queries", spec.queries_path, "--query", to_string(spec.query_type),
                                         "--repeat", std::to_string(spec.repeat), "--out", child_path};
        if (!spec.truth_path.empty()) {
          args.push_back("--truth");
          args.push_back(spec.truth_path);
        }
        std::remove(result_path.c_str());
        std::remove(child_path.c_str());
        auto oc = run_child(args, cfg.timeout_s, cfg.memory_limit_mb, (logs / (j.id + ".log")).string());
        const bool wrote = read_json(child_path, &result);
        // Interrupted: keep a job that finished on its own, drop one the interrupt killed.
        if (g_interrupted && !(wrote && oc.exited)) {
          std::remove(child_path.c_str());
          break;
        }
        if (!wrote) result = status_row(spec, j, oc, cfg.timeout_s);
        result["job"]["id"] = j.id;
        result["job"]["mesh"]["name"] = j.mesh.name;
        result["elapsed_seconds"] = oc.seconds;
      }
      result["job"]["suite"] = cfg.name;
      write_json_atomic(result_path, result);
      std::remove(child_path.c_str());
      done.push_back(result);
      summary_rows[j.id] = result;
      write_summary();
      ++finished;
      spent += std::chrono::duration<double>(std::chrono::steady_clock::now() - tj).count();
      double left = spent / double(finished) * double(to_run > finished ? to_run - finished : 0);
      std::cerr << "[" << (i + 1) << "/" << jobs.size() << "] " << j.id << ": " << short_result(result)
                << "  (elapsed " << format_seconds(std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count())
                << ", left ~" << format_seconds(left) << ")\n";
    }
    write_summary();
    if (g_interrupted) {
      std::cerr << "suite: interrupted; " << done.size() << " job(s) kept. Run again with --resume to finish.\n";
      throw ExitCode{130};
    }
    std::size_t not_ok = std::count_if(done.begin(), done.end(), [](const json& r) { return r.value("status", "") != "ok"; });
    std::cerr << "suite " << cfg.name << ": " << done.size() << " job(s) (" << skipped << " resumed), " << not_ok
              << " not ok; results in " << out.string() << "\n";
  });
}

}  // namespace bvhbench
