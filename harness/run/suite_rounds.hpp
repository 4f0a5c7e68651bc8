#pragma once
/// A suite run in rounds (SuiteConfig::rounds, suites/README.md "Rounds"): every job run N times,
/// round after round over the whole suite, each job's result the best of its rounds
/// (round_merge.hpp). Here: where each round of a job keeps its files, whether `--resume` may skip
/// a round, the order of a round's structures, and the book of each job's rounds until it has
/// them all. The loop that runs them is suite_runner.cpp.
///
/// Layout in OUT with N > 1 rounds: rounds/ID.round<k>.json (round k's complete result, written
/// atomically, kept after the merge), rounds/ID.round<k>.json.child (its child's, until recorded),
/// logs/ID.round<k>.log, logs/GROUP.round<k>.plan.json and .built.json; runs/ID.json is the merged
/// result, written when every round has one. Not runs/ID.round<k>.json: every reader of a result
/// folder (the report, compare, the estimate) takes each runs/*.json for a job.
/// With one round nothing changes: the round's files are runs/ID.json, logs/ID.log,
/// logs/GROUP.plan.json, as they always were.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/run/build_groups.hpp"
#include "harness/run/suite.hpp"

namespace bvhbench {

/// Where round `round` (1-based) of a suite of `rounds` rounds keeps a job's files.
struct RoundFiles {
  std::string result;  ///< OUT/runs/ID.json with one round, else OUT/rounds/ID.round<k>.json
  std::string child;   ///< result + ".child": where the job's child leaves its result
  std::string log;     ///< OUT/logs/ID.log with one round, else OUT/logs/ID.round<k>.log
};
RoundFiles round_files(const std::string& out, const JobPlan& job, int round, int rounds);

/// Where round `round` keeps a group's plan and its child's word that the build is done
/// (group_plan.hpp): OUT/logs/GROUP.plan.json (.built.json), or GROUP.round<k>.plan.json.
struct GroupRoundFiles {
  std::string plan;
  std::string built;
};
GroupRoundFiles group_round_files(const std::string& out, const std::string& group_id, int round, int rounds);

/// Whether `--resume` skips round `round` of the job: its result is recorded and is not
/// `not_run` (its structure's child died before it: run again), or its child left one to adopt.
bool round_done(const std::string& out, const JobPlan& job, int round, int rounds);

/// The order of one round's structures, each group run once per round (a fresh child, a fresh
/// build). Mesh after mesh, in the order of each mesh's first job, every group of a mesh together:
/// the methods compared on one mesh are then timed next to each other, not a suite apart. The
/// structures' own order (group_by_structure: by first job) does not give that, since a suite's
/// matrices repeat the meshes: headline.yml's out-of-core jobs on the 32M bunny come after every
/// in-memory structure of every model, the 32M scan-like model's between them.
/// Within a mesh, the groups in suite order on odd rounds and reversed on even ones (A B, then
/// B A): a drift of the machine across one mesh's stretch then favours no method over both rounds.
std::vector<BuildGroup> round_order(const std::vector<BuildGroup>& groups, const std::vector<JobPlan>& jobs,
                                    int round);

/// Each job's rounds as they are recorded, until the job has every one.
class RoundBook {
 public:
  explicit RoundBook(int rounds) : rounds_(rounds) {}

  /// A job whose rounds are all in.
  struct Complete {
    nlohmann::json result;  ///< the round's result with one round, else merge_rounds() of them all
    bool resumed = false;   ///< every round was taken from an earlier run
  };

  /// Round `round` (1-based) of job `job` has `result`; `ran_now`: run by this invocation (not
  /// resumed or adopted). The job's result once this was the last of its rounds missing.
  std::optional<Complete> add(std::size_t job, int round, nlohmann::json result, bool ran_now);

 private:
  struct JobRounds {
    std::vector<nlohmann::json> results;  // by round - 1; null until recorded
    std::size_t recorded = 0;
    bool ran_now = false;
  };
  int rounds_;
  std::vector<JobRounds> jobs_;  // by job index, grown as needed
};

}  // namespace bvhbench
