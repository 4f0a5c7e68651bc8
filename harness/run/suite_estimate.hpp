#pragma once
/// How long a suite is expected to take, said by `bvhbench suite` before it runs (and by
/// `suite --estimate` without running), and the time left after each job.
///
/// A job is priced in three parts, each from the results already on disk ("observations": the
/// suite's own folder from an earlier run, every results/*/ of this checkout, the committed
/// baseline and the report tests' fixture), scaled to the job's mesh and query set:
///  - the build, once per structure (a group of jobs that share one, build_groups.hpp): the
///    nearest observed build of the same method and options (else of the method), scaled by
///    T log T in the triangle count T;
///  - the queries: (repeat + 2) passes (the counted warm-up, the timed ones, the latency pass)
///    of n queries at the most similar observation's rate (same method, query type, options,
///    query kind; the nearest size), a query costing more with the depth of a hierarchy
///    (log T);
///  - the rest: a child's start, the calibration and the accuracy (a fixed part) and, once per
///    structure, loading the mesh (per triangle): fitted over every observation.
/// A suite run in rounds (SuiteConfig::rounds) pays all three once per round: each round runs
/// every job again, on a structure built again.
/// Each observation's build and queries are first brought to this machine as it is now: scaled
/// by the calibration kernel (calibration.hpp) timed here against the kernel its result recorded,
/// so results made on a faster machine, or on this one while it was busy, price what they would
/// cost here.
/// A method without any observation is priced at the median rates of the methods that have.
/// Query sets and oracles not in the cache yet come on top: mesh loading, and the oracle's cost
/// per triangle and per query.
///
/// The triangle count of a mesh that does not exist yet (`make paper` before its data) comes
/// from the dataset manifest beside it, else from its preset's declared size
/// (datasets-scripts/preset_sizes.json, which make_datasets.py --declared-sizes writes): a
/// suite is priced at its real size before its data is made.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/run/build_groups.hpp"
#include "harness/run/suite.hpp"

namespace bvhbench {

/// What a finished job measured, as the estimate reads it.
struct CostObservation {
  std::string method, params_key, query, kind;
  bool batch = false;
  double triangles = 1, n = 1;
  double build_seconds = 0;      ///< 0 when the build was another job's (a later job of a group)
  double query_seconds = 0;      ///< per query, one thread (1 / median throughput x threads)
  double rest_seconds = 0;       ///< elapsed - build - passes: start, loading, calibration, accuracy
  bool loaded_mesh = true;       ///< the job's child loaded the mesh (first of its group, or alone)
  double kernel_seconds = 0;     ///< the calibration kernel's median beside it (0: none, or another kernel)
};

/// Reads a result as an observation; false for one that did not run ok or has no elapsed time.
bool observe(const nlohmann::json& result, CostObservation* out);

/// The triangles of a mesh at `path`: its file's header (PLY, OFF, binary STL; OBJ face lines),
/// else the manifest beside it, else its preset's declared size; 0 when nothing says.
double mesh_triangles(const std::string& path);

/// The expected time of a suite's jobs.
struct SuitePrice {
  std::vector<double> job_seconds;  ///< by job, over its rounds to run (0 for a job that will not run)
  std::vector<double> build_seconds;  ///< by job, the part of job_seconds that builds its structure
  std::vector<int> job_runs;        ///< by job, the rounds it is priced for (0 for a job that will not run)
  double data_seconds = 0;          ///< query sets and oracles still to make
  int rounds = 1;                   ///< the suite's rounds
  std::size_t jobs = 0;             ///< jobs priced (to run in at least one round)
  std::size_t runs = 0;             ///< job runs priced: each job once per round it has to run
  std::size_t builds = 0;           ///< structures built for them, over the rounds
  std::size_t observations = 0;     ///< results it learned from
  std::size_t unknown_meshes = 0;   ///< meshes of unknown size (priced as 1 triangle)
  std::size_t guessed = 0;          ///< jobs of a method never observed
  std::size_t rescaled = 0;         ///< results whose speed was scaled to this machine by over 10 %
  double total() const;
  /// The expected seconds of one run (one round) of job `job`: job_seconds / job_runs.
  double run_seconds(std::size_t job) const;
  /// "N job(s) to run[ in R rounds (M run(s))], B build(s): expected ~T (jobs .., query sets and
  /// oracles ..; from O results)".
  std::string describe() const;
};

/// `suite --estimate --json`: the total and its parts, and each job to run with its expected
/// seconds over its rounds, the build's part of them and its runs (where the time of a suite
/// goes, before it runs).
nlohmann::json price_json(const SuitePrice& price, const std::vector<JobPlan>& jobs);

class SuiteEstimator {
 public:
  /// Learns from the results of `folders` (each a suite's result folder, or a folder of runs),
  /// their builds and queries scaled to a machine whose calibration kernel takes
  /// `kernel_seconds_here` (0: taken as measured).
  explicit SuiteEstimator(const std::vector<std::string>& folders, double kernel_seconds_here = 0);
  /// The default folders: OUT (a previous run), every results/*/ of this checkout, the
  /// committed baseline and the report tests' fixture.
  static std::vector<std::string> default_folders(const std::string& out);

  /// Prices `jobs[i]` in each round r for which to_run[r][i] (one vector per round of the suite,
  /// each of jobs.size()), built once per group of `groups` in each round (each job alone when
  /// `shared_builds` is false), with the suite's repeat and truth; the query sets and oracles not
  /// cached under `data_dir` on top, once.
  SuitePrice price(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs,
                   const std::vector<std::vector<bool>>& to_run, const std::vector<BuildGroup>& groups,
                   bool shared_builds, const std::string& data_dir) const;

  std::size_t observations() const { return obs_.size(); }

 private:
  void fit_rest();
  void scale_to_machine(double kernel_seconds_here);
  /// One round of `to_run` into `p` (job_seconds, build_seconds, job_runs, runs, builds);
  /// `guessed` marks the jobs priced without an observation of their method.
  void price_round(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const std::vector<bool>& to_run,
                   const std::vector<BuildGroup>& groups, bool shared_builds,
                   const std::function<double(const JobPlan&)>& triangles, SuitePrice& p,
                   std::vector<bool>& guessed) const;
  double build_seconds(const JobPlan& job, double triangles, bool* known) const;
  double data_seconds(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const std::vector<bool>& to_run,
                      const std::string& data_dir, const std::function<double(const JobPlan&)>& triangles) const;
  double query_seconds(const JobPlan& job, double triangles, bool* known) const;
  std::vector<CostObservation> obs_;
  double rest_fixed_ = 0.5, rest_per_triangle_ = 0;  // fitted in the constructor
  double median_build_per_triangle_ = 0, median_query_ = 0;
  std::size_t rescaled_ = 0;
};

/// The time left: `expected_left` (the jobs not finished, as priced) scaled by how the finished
/// ones' actual seconds compared with their price (the ratio held within [1/20, 20]).
double time_left(double expected_left, double expected_done, double actual_done);

}  // namespace bvhbench
