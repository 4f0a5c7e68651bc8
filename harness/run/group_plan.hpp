#pragma once
/// What a child that runs the jobs of one structure is told (`bvhbench run-group --plan FILE`,
/// harness/cli/run_group_command.cpp): the jobs, each with where its result and its output go,
/// the shared build's id, and where to say that the build is done. The suite's local executor
/// writes it as OUT/logs/GROUP.plan.json (local_job_executor.hpp).
///
/// {"build_id": "cow__ebp_octree", "built": "OUT/logs/GROUP.built.json",
///  "jobs": [{"mesh": .., "method": "NAME:k=v", "queries": .., "query": "inside", "repeat": 5,
///            "threads": 1, "truth": ".." | "", "out": "OUT/runs/ID.json.child",
///            "log": "OUT/logs/ID.log"}, ...]}
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/run/run_job.hpp"

namespace bvhbench {

struct GroupPlanJob {
  JobSpec spec;     ///< method resolved when the plan is read (Registry::describe)
  std::string out;  ///< where the child writes the job's result, atomically, when it is final
  std::string log;  ///< where the child's output goes while the job runs
};

struct GroupPlan {
  std::string build_id;  ///< build.id of every result
  std::string built;     ///< where the child writes the build block once built ("": nowhere)
  std::vector<GroupPlanJob> jobs;
};

nlohmann::json group_plan_to_json(const GroupPlan& plan);
/// Reads a plan. Throws InputError naming `file` when it is not one, or when its jobs do not
/// share one structure (mesh, method spec, threads, repeat).
GroupPlan group_plan_from_json(const nlohmann::json& j, const std::string& file);

}  // namespace bvhbench
