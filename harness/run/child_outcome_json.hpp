#pragma once
/// A child's end (child_process.hpp: ChildOutcome) as JSON, for a child run on another machine:
/// `bvhbench run-child` prints it there, and the suite's executor reads it back here to make the
/// job's status row (job_status.hpp) exactly as if the child had been its own.
///
/// {"exited": bool, "exit_code": int, "signal": int, "timed_out": bool, "seconds": number,
///  "stderr_tail": string}
#include <nlohmann/json.hpp>

#include "harness/run/child_process.hpp"

namespace bvhbench {

nlohmann::json child_outcome_to_json(const ChildOutcome& outcome);

/// The outcome from its JSON; a missing or mistyped member keeps its default (a peer that sent
/// less is read as far as it goes, never thrown over: the job still gets a status row).
ChildOutcome child_outcome_from_json(const nlohmann::json& j);

}  // namespace bvhbench
