#pragma once
/// The data a suite's jobs share: each query set generated once (`bvhbench queries`) and each
/// oracle file computed once (`bvhbench truth`), both in child processes (a bad mesh must not
/// end the suite), cached in DATA/queries and DATA/truth across runs. They are made where the
/// runner is, before a job is handed to its executor; an executor on other machines needs DATA
/// on a file system they share.
#include <map>
#include <string>

#include "harness/run/child_process.hpp"
#include "harness/run/suite.hpp"

namespace bvhbench {

/// A job's query set: `path` (a .npy with its sidecar, or a points file), or `error` when it
/// could not be made or read ("" path).
struct QuerySetFile {
  std::string path;
  std::string error;
};

class SuiteData {
 public:
  /// `data` holds the cache (DATA/queries, DATA/truth: created if missing); `logs` the children's
  /// output (queries__MESH__LABEL.log, truth__MESH__LABEL.log). `exe` is the bvhbench to run.
  /// Query generation runs under `limits`; the oracle under the same memory limit and at least
  /// 30 minutes. Without `truth`, truth() is always "".
  SuiteData(std::string data, std::string logs, std::string exe, ChildLimits limits, bool truth);

  /// The job's query set. A generated one is reused when its sidecar names the job's mesh path
  /// and that file's sha256, and made otherwise; a points file is only checked to be a readable
  /// regular file (each job reads it: a malformed one is its rejected_input).
  QuerySetFile queries(const JobPlan& job);
  /// The oracle file for the job's mesh and the query set `npy`, "" when there is none: truth is
  /// off, `npy` is "", the oracle failed (reported on stderr), or it once said "not implemented"
  /// (then no more are tried).
  std::string truth(const JobPlan& job, const std::string& npy);

 private:
  std::string data_, logs_, exe_;
  ChildLimits limits_;
  bool truth_ = true;
  bool truth_unavailable_ = false;
  std::map<std::string, QuerySetFile> query_sets_;  // mesh path|label -> made
  std::map<std::string, std::string> truths_;       // mesh path|npy -> oracle file ("" = none)
};

}  // namespace bvhbench
