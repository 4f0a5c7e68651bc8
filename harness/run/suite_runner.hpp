#pragma once
/// The loop of `bvhbench suite`: each job of a suite handed to an executor (job_executor.hpp)
/// once its query set and oracle are made (suite_data.hpp), its result written atomically to
/// OUT/runs/ID.json with the job's identity, summary.csv rewritten after each, progress and a
/// time-left estimate on stderr. With `resume`, a job whose result is there is skipped, and one
/// whose child finished but whose runner was killed before recording it (ID.json.child) is
/// adopted. An interrupt (interrupt.hpp) keeps what finished and stops.
///
/// Layout of OUT: suite.yml (a copy of the suite file), runs/ID.json, logs/ID.log (a job's
/// output), logs/queries__*.log and logs/truth__*.log, summary.csv, data/ (the default cache), and
/// suite.lock while a run writes it (folder_lock.hpp).
#include <cstddef>
#include <string>
#include <vector>

#include "harness/run/job_executor.hpp"
#include "harness/run/suite.hpp"

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

/// Runs `jobs` (a subset of cfg.jobs, in order) of the suite `cfg` with `executor`.
/// summary.csv covers every job of cfg that has a result in OUT, in suite order, not only the
/// ones run now. Throws InputError when a result cannot be written.
SuiteRunSummary run_suite(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
                          JobExecutor& executor);

}  // namespace bvhbench
