// Reading a suite file: the YAML parsed, checked and expanded into its jobs (suite.hpp).
#include "harness/run/suite.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/run/suite_schema.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/sha256.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// Plans and ids
// ---------------------------------------------------------------------------------------------
std::string file_safe(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum((unsigned char)c) || c == '.' || c == '-' || c == '=' || c == '_') ? c : '_';
  return o;
}

std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

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
  if (!n.IsScalar()) suite_error(file, n, what + " must be a scalar");
  return n.as<std::string>();
}

// `all` or {all: true, except: [NAME, ...]}: every registered method with the default sweep its
// folder declares (MethodInfo::sweep), so that a new method folder reaches such a matrix with no
// other file changed.
std::vector<std::string> expand_all(const std::string& file, const YAML::Node& n) {
  std::vector<std::string> except;
  if (n.IsMap()) {
    check_suite_keys(file, n, SuiteLevel::all_methods);
    bool all = false;
    try {
      all = n["all"].as<bool>();
    } catch (const YAML::Exception&) {
      suite_error(file, n["all"], "all: is true or false");
    }
    if (!all) return {};
    for (auto x : as_list(n["except"])) {
      const std::string name = scalar(file, x, "a method name in except:");
      if (!Registry::global().find(name) && !Registry::global().is_left_out(name))
        suite_error(file, x, "except: names no method: '" + name + "'");
      except.push_back(name);
    }
  }
  return Registry::global().all_method_specs(except);
}

// The declared options of the method `name`, to tell one given beside `name:` (none when the
// method is unknown: its name is refused once the spec is resolved).
const std::vector<ParamSpec>& declared_options(const std::string& name) {
  static const std::vector<ParamSpec> none;
  const MethodInfo* m = Registry::global().find(name);
  return m ? m->params : none;
}

// Expands {name: m, params: {a: [1, 2], b: x}} into "m:a=1,b=x", "m:a=2,b=x".
std::vector<std::string> expand_method(const std::string& file, const YAML::Node& n) {
  if (n.IsScalar() && n.as<std::string>() == "all") return expand_all(file, n);
  if (n.IsMap() && n["all"]) return expand_all(file, n);
  if (n.IsScalar()) return {n.as<std::string>()};
  if (!n.IsMap() || !n["name"]) suite_error(file, n, "a method is NAME, NAME:k=v or {name:, params:}");
  std::string name = scalar(file, n["name"], "method name");
  check_suite_keys(file, n, SuiteLevel::method, declared_options(name));
  std::vector<std::string> specs = {""};
  if (auto ps = n["params"]) {
    if (!ps.IsMap()) suite_error(file, ps, "method params must be a map");
    std::vector<std::pair<std::string, std::vector<std::string>>> axes;
    for (auto kv : ps) {
      std::vector<std::string> vals;
      for (auto v : as_list(kv.second)) vals.push_back(scalar(file, v, "parameter value"));
      if (vals.empty()) suite_error(file, kv.second, "empty value list for " + kv.first.as<std::string>());
      axes.push_back({kv.first.as<std::string>(), vals});
    }
    for (auto& [k, vals] : axes) {
      if (specs.size() * vals.size() > kMaxSuiteJobs)
        suite_error(file, n, "the parameter sweep makes more than " + std::to_string(kMaxSuiteJobs) + " variants");
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
    if (n[key]) suite_error(suite, n, std::string("a points file ({file:, name:}) takes no '") + key + "'");
  check_suite_keys(suite, n, SuiteLevel::points_file);
  QueryPlan q;
  q.kind = "file";
  q.file = scalar(suite, n["file"], "file");
  if (q.file.empty()) suite_error(suite, n, "file: is empty");
  if (fs::path(q.file).is_relative()) q.file = (base / q.file).lexically_normal().string();
  q.name = n["name"] ? scalar(suite, n["name"], "name") : fs::path(q.file).stem().string();
  if (q.name.empty()) suite_error(suite, n, "name: is empty");
  auto [it, fresh] = labels.emplace(q.label(), q.file);
  if (!fresh && it->second != q.file)
    suite_error(suite, n, "two points files are named '" + q.name + "' (" + it->second + " and " + q.file +
                             "); give one a name: to tell their jobs apart");
  return q;
}

// The query set's `params:`, each checked against the kind's declaration where it stands.
std::map<std::string, double> query_set_params(const std::string& file, const QueryKind& kind, const YAML::Node& ps) {
  if (!ps.IsMap()) suite_error(file, ps, "a query set's params: is a map {name: value}");
  std::map<std::string, double> out;
  for (auto kv : ps) {
    const std::string key = kv.first.as<std::string>();
    const std::string text = scalar(file, kv.second, "query kind parameter " + key);
    try {
      out[key] = query_kind_params(kind, {{key, text}}).get_real(key);
    } catch (const InputError& e) {
      suite_error(file, kv.first, e.what());
    }
  }
  return out;
}

// A generated query set: a kind alone, or {kind:, n:, seed:, params:}.
QueryPlan generated_query_plan(const std::string& file, const YAML::Node& n) {
  QueryPlan q;
  if (!n.IsScalar() && !n.IsMap())
    suite_error(file, n, "a query set is a kind, {kind:, n:, seed:, params:} or {file:, name:}");
  if (n.IsMap() && n["name"]) suite_error(file, n, "name: is for a points file ({file: PATH, name: NAME})");
  try {
    q.kind = n.IsScalar() ? n.as<std::string>() : n["kind"] ? n["kind"].as<std::string>() : q.kind;
  } catch (const YAML::Exception& e) {
    suite_error(file, n, std::string("bad query set: ") + e.what());
  }
  if (q.kind == "file") suite_error(file, n, "a points file is given as {file: PATH}");
  const QueryKind* kind = nullptr;
  try {
    kind = &query_kind(q.kind);
  } catch (const InputError& e) {  // names the known kinds and the nearest one
    suite_error(file, n, e.what());
  }
  if (!n.IsMap()) return q;
  check_suite_keys(file, n, SuiteLevel::query_set, kind->params);
  try {
    if (n["n"]) q.n = n["n"].as<std::size_t>();
    if (n["seed"]) q.seed = n["seed"].as<std::uint64_t>();
  } catch (const YAML::Exception& e) {
    suite_error(file, n, std::string("bad query set: ") + e.what());
  }
  if (n["params"]) q.params = query_set_params(file, *kind, n["params"]);
  if (q.n == 0) suite_error(file, n, "n must be > 0");
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

// `rounds:`, an integer from 1 to kMaxSuiteRounds; a bad one is named with its line and text.
int read_rounds(const YAML::Node& node, const std::string& path) {
  const std::string range = "rounds must be an integer from 1 to " + std::to_string(kMaxSuiteRounds);
  if (!node.IsScalar()) suite_error(path, node, range + " (times each job is run), not a list or a map");
  int rounds = 0;
  try {
    rounds = node.as<int>();
  } catch (const YAML::Exception&) {
    suite_error(path, node, range + " (times each job is run), not '" + node.Scalar() + "'");
  }
  if (rounds < 1 || rounds > kMaxSuiteRounds) suite_error(path, node, range + ", not " + node.Scalar());
  return rounds;
}

// The top level's settings (repeat, rounds, timeout_s, memory_limit_mb, truth, name) into `cfg`.
void read_settings(const YAML::Node& root, const std::string& path, SuiteConfig& cfg) {
  if (root["rounds"]) cfg.rounds = read_rounds(root["rounds"], path);
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
}

std::vector<MeshPlan> read_meshes(const std::string& path, const YAML::Node& list, const fs::path& base) {
  std::vector<MeshPlan> meshes;
  for (auto n : as_list(list)) {
    MeshPlan mp;
    if (n.IsScalar()) {
      mp.path = n.as<std::string>();
    } else if (n.IsMap() && n["path"]) {
      check_suite_keys(path, n, SuiteLevel::mesh);
      mp.path = n["path"].as<std::string>();
      if (n["name"]) mp.name = n["name"].as<std::string>();
    } else {
      suite_error(path, n, "a mesh is a path or {path:, name:}");
    }
    if (fs::path(mp.path).is_relative()) mp.path = (base / mp.path).lexically_normal().string();
    if (mp.name.empty()) mp.name = fs::path(mp.path).stem().string();
    meshes.push_back(mp);
  }
  return meshes;
}

std::vector<QueryType> read_query_types(const std::string& path, const YAML::Node& m) {
  std::vector<QueryType> types;
  for (auto n : as_list(m["query"] ? m["query"] : YAML::Node(std::vector<std::string>{"inside", "distance"}))) {
    try {
      types.push_back(parse_query_type(n.as<std::string>()));
    } catch (const InputError& e) {
      suite_error(path, n, e.what());
    }
  }
  return types;
}

std::vector<MethodSpec> read_methods(const std::string& path, const YAML::Node& list) {
  std::vector<MethodSpec> methods;
  for (auto n : as_list(list))
    for (auto& s : expand_method(path, n)) {
      // Parsed and resolved once, now: a typo in a suite is bad input, not 40 failed jobs. A
      // method this build left out (a Python method whose package is not installed) is no typo:
      // its jobs stay in the suite, unresolved, and become `unsupported` rows with the reason.
      MethodSpec spec = Registry::global().describe(s);
      if (!spec.resolved() && !Registry::global().is_left_out(spec.name)) suite_error(path, n, spec.problem);
      methods.push_back(std::move(spec));
      if (methods.size() > kMaxSuiteJobs)
        suite_error(path, n, "more than " + std::to_string(kMaxSuiteJobs) + " method variants in one matrix");
    }
  return methods;
}

// The thread axis: query threads per job (default 1), each count once.
std::vector<int> read_thread_counts(const std::string& path, const YAML::Node& m) {
  std::vector<int> thread_counts;
  for (auto n : as_list(m["threads"] ? m["threads"] : YAML::Node(1))) {
    int t = 0;
    try {
      t = n.as<int>();
    } catch (const YAML::Exception&) {
      suite_error(path, n, "threads: is a thread count or a list of them");
    }
    if (t < 1 || t > kMaxJobThreads)
      suite_error(path, n, "threads must be between 1 and " + std::to_string(kMaxJobThreads));
    if (std::find(thread_counts.begin(), thread_counts.end(), t) == thread_counts.end()) thread_counts.push_back(t);
  }
  if (thread_counts.empty()) suite_error(path, m, "threads: is an empty list");
  return thread_counts;
}

/// One matrix's axes, read and checked.
struct MatrixAxes {
  std::vector<MeshPlan> meshes;
  std::vector<QueryPlan> queries;
  std::vector<QueryType> types;
  std::vector<MethodSpec> methods;
  std::vector<int> threads;
  double jobs() const {  // in floating point: the product may not fit in 64 bits
    return double(meshes.size()) * double(queries.size()) * double(types.size()) * double(methods.size()) *
           double(threads.size());
  }
};

MatrixAxes read_matrix(const std::string& path, const YAML::Node& m, const fs::path& base,
                       std::map<std::string, std::string>& query_files) {
  if (!m.IsMap()) suite_error(path, m, "each matrix is a map");
  check_suite_keys(path, m, SuiteLevel::matrix);
  for (const char* key : {"meshes", "queries", "methods"})
    if (!m[key]) suite_error(path, m, std::string("matrix without '") + key + "'");
  MatrixAxes axes;
  axes.meshes = read_meshes(path, m["meshes"], base);
  for (auto n : as_list(m["queries"]))
    axes.queries.push_back(n.IsMap() && n["file"] ? file_query_plan(path, n, base, query_files)
                                                  : generated_query_plan(path, n));
  axes.types = read_query_types(path, m);
  axes.methods = read_methods(path, m["methods"]);
  axes.threads = read_thread_counts(path, m);
  return axes;
}

// "<mesh>__<query set>__<query>__<method spec>[__t<T>]", file-safe, at most 200 characters.
std::string job_id(const MeshPlan& mesh, const QueryPlan& q, QueryType t, const MethodSpec& spec, int threads) {
  // One thread keeps the id it always had; more add "__t<T>".
  std::string id = file_safe(mesh.name + "__" + q.label() + "__" + to_string(t) + "__" + spec.text +
                             (threads == 1 ? std::string() : "__t" + std::to_string(threads)));
  if (id.size() > 200) id = id.substr(0, 180) + "-" + sha256_hex(id.data(), id.size()).substr(0, 12);
  return id;
}

// The matrix's jobs, in axis order, each id once over the suite (`seen`).
void add_jobs(const MatrixAxes& axes, std::set<std::string>& seen, std::vector<JobPlan>& jobs) {
  for (auto& mesh : axes.meshes)
    for (auto& q : axes.queries)
      for (auto t : axes.types)
        for (auto& spec : axes.methods)
          for (int threads : axes.threads) {
            JobPlan j{job_id(mesh, q, t, spec, threads), mesh, q, t, spec, threads};
            if (seen.insert(j.id).second) jobs.push_back(j);
          }
}

/// The suite of the YAML document `root` of the file `path` (load_suite). Throws InputError, or a
/// YAML::Exception where a value of the wrong shape is read (see parse_suite).
SuiteConfig expand_suite(const YAML::Node& root, const std::string& path) {
  SuiteConfig cfg;
  cfg.file = path;
  if (!root.IsMap()) throw file_error(path, "a suite is a YAML map (see suites/README.md)");
  check_suite_keys(path, root, SuiteLevel::top);
  read_settings(root, path, cfg);
  auto matrices = root["matrices"];
  if (!matrices || !matrices.IsSequence() || matrices.size() == 0)
    throw file_error(path, "missing 'matrices:' (a list of {meshes, queries, query, methods})");
  const fs::path base = fs::path(path).parent_path();
  std::set<std::string> seen;
  std::map<std::string, std::string> query_files;  // label -> file, across matrices
  double expanded = 0;                              // jobs of the matrices so far, duplicates included
  for (auto m : matrices) {
    const MatrixAxes axes = read_matrix(path, m, base, query_files);
    expanded += axes.jobs();  // before the product is made
    if (expanded > double(kMaxSuiteJobs))
      suite_error(path, m, "the suite expands to more than " + std::to_string(kMaxSuiteJobs) +
                              " jobs (meshes x query sets x queries x method variants, over all matrices): split it");
    add_jobs(axes, seen, cfg.jobs);
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

}  // namespace bvhbench
