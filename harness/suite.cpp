#include "suite.hpp"

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
#include <yaml-cpp/yaml.h>

#include "commands.hpp"
#include "errors.hpp"
#include "progress.hpp"
#include "query_set.hpp"
#include "registry.hpp"
#include "run_job.hpp"
#include "sha256.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// Plans and ids
// ---------------------------------------------------------------------------------------------
namespace {

std::string safe(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum((unsigned char)c) || c == '.' || c == '-' || c == '=' || c == '_') ? c : '_';
  return o;
}

std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

std::string QueryPlan::label() const {
  if (!file.empty()) return "file-" + name;
  std::string s = kind + "-n" + std::to_string(n) + "-s" + std::to_string(seed);
  if (!params.empty()) {
    std::string p;
    for (auto& [k, v] : params) p += k + "=" + format_number(v) + ";";
    s += "-" + sha256_hex(p.data(), p.size()).substr(0, 8);
  }
  return s;
}

namespace {

[[noreturn]] void yaml_error(const std::string& file, const YAML::Node& node, const std::string& what) {
  std::string where = node.Mark().line >= 0 ? " (line " + std::to_string(node.Mark().line + 1) + ")" : "";
  throw file_error(file, what + where);
}

std::vector<YAML::Node> as_list(const YAML::Node& n) {
  std::vector<YAML::Node> out;
  if (!n) return out;
  if (n.IsSequence())
    for (auto x : n) out.push_back(x);
  else
    out.push_back(n);
  return out;
}

std::string scalar(const std::string& file, const YAML::Node& n, const std::string& what) {
  if (!n.IsScalar()) yaml_error(file, n, what + " must be a scalar");
  return n.as<std::string>();
}

// Expands {name: m, params: {a: [1, 2], b: x}} into "m:a=1,b=x", "m:a=2,b=x".
std::vector<std::string> expand_method(const std::string& file, const YAML::Node& n) {
  if (n.IsScalar()) return {n.as<std::string>()};
  if (!n.IsMap() || !n["name"]) yaml_error(file, n, "a method is NAME, NAME:k=v or {name:, params:}");
  std::string name = scalar(file, n["name"], "method name");
  std::vector<std::string> specs = {""};
  if (auto ps = n["params"]) {
    if (!ps.IsMap()) yaml_error(file, ps, "method params must be a map");
    std::vector<std::pair<std::string, std::vector<std::string>>> axes;
    for (auto kv : ps) {
      std::vector<std::string> vals;
      for (auto v : as_list(kv.second)) vals.push_back(scalar(file, v, "parameter value"));
      if (vals.empty()) yaml_error(file, kv.second, "empty value list for " + kv.first.as<std::string>());
      axes.push_back({kv.first.as<std::string>(), vals});
    }
    for (auto& [k, vals] : axes) {
      if (specs.size() * vals.size() > kMaxSuiteJobs)
        yaml_error(file, n, "the parameter sweep makes more than " + std::to_string(kMaxSuiteJobs) + " variants");
      std::vector<std::string> next;
      for (auto& s : specs)
        for (auto& v : vals) next.push_back(s + (s.empty() ? "" : ",") + k + "=" + v);
      specs = next;
    }
  }
  std::vector<std::string> out;
  for (auto& s : specs) out.push_back(s.empty() ? name : name + ":" + s);
  return out;
}

// {file: PATH, name: NAME}: an existing points file as a query set. Two different files may not
// share a name, since it is what tells their jobs apart.
QueryPlan file_query_plan(const std::string& suite, const YAML::Node& n, const fs::path& base,
                          std::map<std::string, std::string>& labels) {
  for (const char* key : {"kind", "n", "seed", "params"})
    if (n[key]) yaml_error(suite, n, std::string("a points file ({file:, name:}) takes no '") + key + "'");
  for (auto kv : n) {
    const std::string key = kv.first.as<std::string>();
    if (key != "file" && key != "name") yaml_error(suite, n, "unknown key '" + key + "' of a points file");
  }
  QueryPlan q;
  q.kind = "file";
  q.file = scalar(suite, n["file"], "file");
  if (q.file.empty()) yaml_error(suite, n, "file: is empty");
  if (fs::path(q.file).is_relative()) q.file = (base / q.file).lexically_normal().string();
  q.name = n["name"] ? scalar(suite, n["name"], "name") : fs::path(q.file).stem().string();
  if (q.name.empty()) yaml_error(suite, n, "name: is empty");
  auto [it, fresh] = labels.emplace(q.label(), q.file);
  if (!fresh && it->second != q.file)
    yaml_error(suite, n, "two points files are named '" + q.name + "' (" + it->second + " and " + q.file +
                             "); give one a name: to tell their jobs apart");
  return q;
}

}  // namespace

SuiteConfig load_suite(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw file_error(path, "cannot read suite file");
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return parse_suite(text, path);
}

namespace {

/// The suite of the YAML document `root` of the file `path` (load_suite). Throws InputError, or a
/// YAML::Exception where a value of the wrong shape is read (see parse_suite).
SuiteConfig expand_suite(const YAML::Node& root, const std::string& path) {
  SuiteConfig cfg;
  cfg.file = path;
  if (!root.IsMap()) throw file_error(path, "a suite is a YAML map (see suites/README.md)");
  const fs::path base = fs::path(path).parent_path();
  try {
    cfg.name = root["name"] ? root["name"].as<std::string>() : fs::path(path).stem().string();
    if (root["repeat"]) cfg.repeat = root["repeat"].as<int>();
    if (root["timeout_s"]) cfg.timeout_s = root["timeout_s"].as<double>();
    if (root["memory_limit_mb"]) cfg.memory_limit_mb = root["memory_limit_mb"].as<double>();
    if (root["truth"]) cfg.truth = root["truth"].as<bool>();
  } catch (const YAML::Exception& e) {
    throw file_error(path, std::string("bad top-level value: ") + e.what());
  }
  if (cfg.repeat < 1) throw file_error(path, "repeat must be >= 1");
  if (!(cfg.timeout_s > 0)) throw file_error(path, "timeout_s must be > 0");
  // The child's address-space limit is set from it (0: none).
  if (!(cfg.memory_limit_mb >= 0 && std::isfinite(cfg.memory_limit_mb)))
    throw file_error(path, "memory_limit_mb must be a number of MiB >= 0 (0 = no limit)");
  auto matrices = root["matrices"];
  if (!matrices || !matrices.IsSequence() || matrices.size() == 0)
    throw file_error(path, "missing 'matrices:' (a list of {meshes, queries, query, methods})");

  std::set<std::string> seen;
  std::map<std::string, std::string> query_files;  // label -> file, across matrices
  double expanded = 0;                              // jobs of the matrices so far, duplicates included
  for (auto m : matrices) {
    if (!m.IsMap()) yaml_error(path, m, "each matrix is a map");
    for (const char* key : {"meshes", "queries", "methods"})
      if (!m[key]) yaml_error(path, m, std::string("matrix without '") + key + "'");
    std::vector<MeshPlan> meshes;
    for (auto n : as_list(m["meshes"])) {
      MeshPlan mp;
      if (n.IsScalar()) {
        mp.path = n.as<std::string>();
      } else if (n.IsMap() && n["path"]) {
        mp.path = n["path"].as<std::string>();
        if (n["name"]) mp.name = n["name"].as<std::string>();
      } else {
        yaml_error(path, n, "a mesh is a path or {path:, name:}");
      }
      if (fs::path(mp.path).is_relative()) mp.path = (base / mp.path).lexically_normal().string();
      if (mp.name.empty()) mp.name = fs::path(mp.path).stem().string();
      meshes.push_back(mp);
    }
    std::vector<QueryPlan> queries;
    for (auto n : as_list(m["queries"])) {
      QueryPlan q;
      if (n.IsMap() && n["file"]) {
        queries.push_back(file_query_plan(path, n, base, query_files));
        continue;
      }
      try {
        if (n.IsScalar()) {
          q.kind = n.as<std::string>();
        } else if (n.IsMap()) {
          if (n["name"]) yaml_error(path, n, "name: is for a points file ({file: PATH, name: NAME})");
          if (n["kind"]) q.kind = n["kind"].as<std::string>();
          if (n["n"]) q.n = n["n"].as<std::size_t>();
          if (n["seed"]) q.seed = n["seed"].as<std::uint64_t>();
          if (n["params"])
            for (auto kv : n["params"]) q.params[kv.first.as<std::string>()] = kv.second.as<double>();
        } else {
          yaml_error(path, n, "a query set is a kind, {kind:, n:, seed:, params:} or {file:, name:}");
        }
      } catch (const YAML::Exception& e) {
        yaml_error(path, n, std::string("bad query set: ") + e.what());
      }
      if (q.kind == "file") yaml_error(path, n, "a points file is given as {file: PATH}");
      if (!find_query_kind(q.kind)) yaml_error(path, n, "unknown query kind '" + q.kind + "'");
      if (q.n == 0) yaml_error(path, n, "n must be > 0");
      queries.push_back(q);
    }
    std::vector<QueryType> types;
    for (auto n : as_list(m["query"] ? m["query"] : YAML::Node(std::vector<std::string>{"inside", "distance"}))) {
      try {
        types.push_back(parse_query_type(n.as<std::string>()));
      } catch (const InputError& e) {
        yaml_error(path, n, e.what());
      }
    }
    std::vector<std::string> methods;
    for (auto n : as_list(m["methods"]))
      for (auto& s : expand_method(path, n)) {
        // Validate now: a typo in a suite is bad input, not 40 failed jobs.
        std::string name;
        std::map<std::string, std::string> given;
        try {
          parse_method_spec(s, &name, &given);
        } catch (const InputError& e) {
          yaml_error(path, n, e.what());
        }
        const MethodInfo* info = Registry::global().find(name);
        if (!info) {
          try {
            Registry::global().create(s);
          } catch (const InputError& e) {
            yaml_error(path, n, e.what());
          }
        }
        try {
          Params::resolve(name, info->params, given);
        } catch (const InputError& e) {
          yaml_error(path, n, e.what());
        }
        methods.push_back(s);
        if (methods.size() > kMaxSuiteJobs)
          yaml_error(path, n, "more than " + std::to_string(kMaxSuiteJobs) + " method variants in one matrix");
      }
    // Before the product is made: its size, in floating point since it may not fit in 64 bits.
    expanded += double(meshes.size()) * double(queries.size()) * double(types.size()) * double(methods.size());
    if (expanded > double(kMaxSuiteJobs))
      yaml_error(path, m, "the suite expands to more than " + std::to_string(kMaxSuiteJobs) +
                              " jobs (meshes x query sets x queries x method variants, over all matrices): split it");
    for (auto& mesh : meshes)
      for (auto& q : queries)
        for (auto t : types)
          for (auto& spec : methods) {
            JobPlan j;
            j.mesh = mesh;
            j.queries = q;
            j.query = t;
            j.method_spec = spec;
            j.id = safe(mesh.name + "__" + q.label() + "__" + to_string(t) + "__" + spec);
            if (j.id.size() > 200) j.id = j.id.substr(0, 180) + "-" + sha256_hex(j.id.data(), j.id.size()).substr(0, 12);
            if (seen.insert(j.id).second) cfg.jobs.push_back(j);
          }
  }
  return cfg;
}

}  // namespace

SuiteConfig parse_suite(const std::string& yaml, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw file_error(path, std::string("malformed YAML: ") + e.what());
  }
  // A value of the wrong shape where a string or a number is read (a map as a mesh path, a list
  // as a parameter name) is bad input like any other; yaml-cpp's message names its line.
  try {
    return expand_suite(root, path);
  } catch (const YAML::Exception& e) {
    throw file_error(path, std::string("bad value: ") + e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// summary.csv
// ---------------------------------------------------------------------------------------------
namespace {

std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) {
    if (c == '"') o += '"';
    o += c == '\n' ? ' ' : c;
  }
  return o + "\"";
}

std::string num(const json& j) {
  if (j.is_null()) return "";
  if (j.is_number_integer() || j.is_number_unsigned()) return std::to_string(j.get<long long>());
  if (j.is_number()) {
    std::ostringstream os;
    os.precision(9);
    os << j.get<double>();
    return os.str();
  }
  if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
  if (j.is_string()) return j.get<std::string>();
  return "";
}

json at(const json& j, std::initializer_list<const char*> path) {
  const json* p = &j;
  for (const char* k : path) {
    if (!p->is_object() || !p->contains(k)) return nullptr;
    p = &(*p)[k];
  }
  return *p;
}

const std::vector<std::string> kCounterColumns = {"nodes_visited", "triangles_tested", "planes_tested",
                                                   "bytes_read", "cache_hit_rate"};

}  // namespace

std::vector<std::string> summary_header() {
  std::vector<std::string> h = {"job_id", "method", "params_key", "mesh", "triangles", "query_kind", "n",
                                "query", "status", "message", "build_s", "structure_bytes",
                                "bytes_per_triangle", "peak_rss_bytes", "query_rss_bytes", "qps_median",
                                "qps_min", "qps_max", "p50_ns", "p99_ns", "p999_ns", "max_ns",
                                "over_deadline", "inside_wrong_rate", "inside_wrong_far",
                                "dist_abs_err_max", "dist_rel_err_p99", "normal_err_p99_deg"};
  for (auto& c : kCounterColumns) h.push_back("c_" + c);
  return h;
}

std::vector<std::string> summary_row(const json& r) {
  auto mesh_name = [&]() -> std::string {
    json n = at(r, {"job", "mesh", "name"});
    if (n.is_string()) return n;
    json p = at(r, {"job", "mesh", "path"});
    return p.is_string() ? fs::path(p.get<std::string>()).stem().string() : "";
  };
  json tris = at(r, {"job", "mesh", "triangles"});
  json sb = at(r, {"build", "structure_bytes"});
  std::string bpt;
  if (tris.is_number() && sb.is_number() && tris.get<double>() > 0) bpt = num(json(sb.get<double>() / tris.get<double>()));
  std::vector<std::string> row = {
      num(at(r, {"job", "id"})), num(at(r, {"job", "method"})), num(at(r, {"job", "params_key"})), mesh_name(),
      num(tris), num(at(r, {"job", "queries", "kind"})), num(at(r, {"job", "queries", "n"})),
      num(at(r, {"job", "query"})), num(at(r, {"status"})), num(at(r, {"message"})),
      num(at(r, {"build", "seconds"})), num(sb), bpt, num(at(r, {"memory", "peak_rss_bytes"})),
      num(at(r, {"memory", "query_rss_bytes"})), num(at(r, {"queries", "throughput_qps", "median"})),
      num(at(r, {"queries", "throughput_qps", "min"})), num(at(r, {"queries", "throughput_qps", "max"})),
      num(at(r, {"queries", "latency_ns", "p50"})), num(at(r, {"queries", "latency_ns", "p99"})),
      num(at(r, {"queries", "latency_ns", "p999"})), num(at(r, {"queries", "latency_ns", "max"})),
      num(at(r, {"queries", "over_deadline"})), num(at(r, {"accuracy", "inside", "rate"})),
      num(at(r, {"accuracy", "inside", "wrong_far"})),
      num(at(r, {"accuracy", "distance", "abs_error", "max"})),
      num(at(r, {"accuracy", "distance", "rel_error", "p99"})),
      num(at(r, {"accuracy", "distance", "normal_angle_deg", "p99"}))};
  for (auto& c : kCounterColumns) row.push_back(num(at(r, {"counters", c.c_str()})));
  for (auto& s : row) s = csv_escape(s);
  return row;
}

void write_summary_csv(const std::string& path, const std::vector<json>& results) {
  std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw file_error(path, "cannot write");
    auto line = [&](const std::vector<std::string>& cells) {
      for (std::size_t i = 0; i < cells.size(); ++i) f << (i ? "," : "") << cells[i];
      f << "\n";
    };
    line(summary_header());
    for (auto& r : results) line(summary_row(r));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw file_error(path, "cannot rename into place");
}

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
  json q = at(r, {"queries", "throughput_qps", "median"});
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
      std::string npy = (data / "queries" / (safe(j.mesh.name) + "__" + j.queries.label() + ".npy")).string();
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
        auto r = run_child(args, cfg.timeout_s, cfg.memory_limit_mb, (logs / ("queries__" + safe(j.mesh.name) + "__" + j.queries.label() + ".log")).string());
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
                           (logs / ("truth__" + safe(j.mesh.name) + "__" + j.queries.label() + ".log")).string());
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
      spec.method_spec = j.method_spec;
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
        std::vector<std::string> args = {exe, "--quiet", "run", "--mesh", spec.mesh_path, "--method", spec.method_spec,
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
