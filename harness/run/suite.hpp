#pragma once
/// Suites: a YAML matrix of jobs (suites/*.yml), read and expanded into job plans here, run by
/// suite_runner.hpp (each job in its own child process with a time limit and an address-space
/// limit, so that a crash, a hang or a blow-up becomes a status row). Format: suites/README.md.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/method.hpp"
#include "harness/core/method_spec.hpp"

namespace bvhbench {

/// How to make one query set, or which points file to take as one.
struct QueryPlan {
  std::string kind = "random";  ///< "file" for a points file
  std::size_t n = 10000;
  std::uint64_t seed = 1;
  std::map<std::string, double> params;
  std::string file;  ///< a points file (.npy, .xyz, .csv), resolved against the suite file's folder
  std::string name;  ///< a points file's short name in job ids (default: its stem)
  /// "random-n10000-s1[-<hash of params>]"; "file-<name>" for a points file.
  std::string label() const;
  /// What `bvhbench queries` is given to make the set, after --mesh and before --out:
  /// --kind K --n N --seed S [--param=k=v ...]. Empty for a points file.
  std::vector<std::string> generator_args() const;
};

struct MeshPlan {
  std::string name;  ///< short name used in job ids
  std::string path;  ///< resolved against the suite file's folder
};

struct JobPlan {
  std::string id;    ///< unique, filesystem-safe, stable across runs
  MeshPlan mesh;
  QueryPlan queries;
  QueryType query = QueryType::inside;
  MethodSpec method;  ///< resolved when the suite was read
  int threads = 1;    ///< query threads (the matrix's `threads:` axis; suites/README.md)
};

/// The most query threads a job may ask for (as `bvhbench run --threads`).
inline constexpr int kMaxJobThreads = 1024;

/// The most rounds a suite may ask for: best of N settles within a handful, and a typo of 300
/// would run the suite 300 times.
inline constexpr int kMaxSuiteRounds = 100;

struct SuiteConfig {
  std::string name;
  std::string file;
  int repeat = 5;
  /// Times every job is run, round-major (suite_runner.hpp): each result is its best round
  /// (round_merge.hpp). 1: each job once, as a suite always did.
  int rounds = 1;
  double timeout_s = 600;
  double memory_limit_mb = 16384;
  bool truth = true;  ///< attach the oracle (bvhbench truth) when it can be computed
  std::vector<JobPlan> jobs;
};

/// The most jobs a suite may expand to (meshes x query sets x queries x method variants, summed
/// over its matrices, before duplicates are dropped). A few hundred bytes of parameter sweeps or
/// aliased matrices can ask for millions, which would take the loader minutes and gigabytes only
/// to list; our largest suite has about 600.
inline constexpr std::size_t kMaxSuiteJobs = 100000;

/// `s` with every character but [A-Za-z0-9.=_-] replaced by '_': job ids and the file names made
/// from them.
std::string file_safe(const std::string& s);
/// A query-set parameter value as labels and the `queries --param` command line write it.
std::string format_number(double v);

/// The jobs `jobs` of the suite `cfg` as JSON, without running anything: the suite's settings
/// and, per job, its id, mesh, query set (how it is made), query type, method (spec, name,
/// canonical key, every option's value), threads, repetitions and rounds. What `bvhbench suite FILE
/// --list --json` prints, and what every tool that needs a suite's jobs reads (suites/README.md).
nlohmann::json suite_jobs_json(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs);

/// Parses and expands a suite file, every map checked against the suite grammar first
/// (suite_schema.hpp). Throws InputError naming the file, the line and the problem.
SuiteConfig load_suite(const std::string& path);
/// The same for the suite text `yaml` of the file `path` (which names it in messages; relative
/// paths in it are resolved against its folder). Reads no file.
SuiteConfig parse_suite(const std::string& yaml, const std::string& path);


}  // namespace bvhbench
