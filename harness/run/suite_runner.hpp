#pragma once
/// The loop of `bvhbench suite`: the jobs of each structure (build_groups.hpp) handed together to
/// an executor (job_executor.hpp) once their query sets and oracles are made (suite_data.hpp),
/// which runs them in one child with one build; each result written atomically to
/// OUT/runs/ID.json with the job's identity, summary.csv rewritten after each, progress and a
/// time-left estimate on stderr. With `resume`, a job whose result is there is skipped (unless it
/// is `not_run`: its group's child died before it), and one
/// whose child finished but whose runner was killed before recording it (ID.json.child) is
/// adopted. An interrupt (interrupt.hpp) keeps what finished and stops.
///
/// With `rounds: N` > 1 (suite_rounds.hpp) all of that happens N times, round-major: every group
/// in round 1, then every group in round 2, ...; each round of a job is recorded on its own
/// (rounds/ID.round<k>.json: `resume` skips the rounds done), and the job's result is merged from
/// its rounds (round_merge.hpp) when it has them all.
///
/// Layout of OUT: suite.yml (a copy of the suite file), runs/ID.json, logs/ID.log (a job's
/// output; the first job of a group's has the shared build's too), logs/GROUP.plan.json and
/// logs/GROUP.built.json (a group's plan, and its child's word that the build is done),
/// logs/queries__*.log and logs/truth__*.log, summary.csv, data/ (the default cache), and
/// suite.lock while a run writes it (folder_lock.hpp); with rounds, rounds/ and each round's logs
/// (suite_rounds.hpp).
#include <cstddef>
#include <string>
#include <vector>

#include "harness/run/job_executor.hpp"
#include "harness/run/suite.hpp"
#include "harness/run/suite_estimate.hpp"

namespace bvhbench {

struct SuiteRunOptions {
  std::string out;       ///< the result folder (created)
  std::string data_dir;  ///< the cache of query sets and oracle files ("": OUT/data)
  bool resume = false;
};

struct SuiteRunSummary {
  std::size_t recorded = 0;  ///< results run or resumed in this invocation
  std::size_t resumed = 0;   ///< of them, taken from an earlier run
  std::size_t not_ok = 0;    ///< of them, with a status other than ok
  bool interrupted = false;
};

/// OUT/runs/ID.json: where a job's result is recorded (with rounds, the one merged from them).
std::string result_path(const SuiteRunOptions& options, const JobPlan& job);

/// The expected time of `jobs` in each of the suite's rounds (with options.resume: of the rounds
/// not done, suite_rounds.hpp: round_done), built once per structure and round when
/// `shared_builds` (suite_estimate.hpp), learned from the results on disk.
SuitePrice estimate_suite(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
                          bool shared_builds);

/// Runs `jobs` (a subset of cfg.jobs, in order) of the suite `cfg` with `executor`: grouped by
/// structure (build_groups.hpp), each group's jobs submitted together (JobExecutor::submit_group),
/// groups in the order of their first job (with rounds: round_order, suite_rounds.hpp), once per
/// round. Says first how long it expects to take
/// (estimate_suite) and, after each job, the time left, corrected by how the jobs so far
/// compared with their price.
/// summary.csv covers every job of cfg that has a result in OUT, in suite order, not only the
/// ones run now. Throws InputError when a result cannot be written.
SuiteRunSummary run_suite(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
                          JobExecutor& executor);

}  // namespace bvhbench
