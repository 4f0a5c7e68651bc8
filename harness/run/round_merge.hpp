#pragma once
/// One result from the rounds of a suite job (suite `rounds:`, suite_runner.hpp). Researchers
/// who compare two methods on a shared machine run them in turn, A B A B ..., and keep the best
/// round of each: the machine's drift between rounds is noise, not the method. This is that rule,
/// written once. The job's result is the kept round's result whole, so its latency percentiles,
/// build, memory and counters are the ones measured beside its throughput, plus a `rounds` record
/// of every round, so that the rounds not kept are not hidden.
///
/// The round kept:
/// - of the rounds that ended ok, the one of the highest median throughput (the earliest of
///   equals; an ok round without a median, which timed no pass, ranks below any with one);
/// - when none ended ok, the first round that ended in a failure of its own (crash, timeout, oom,
///   ...): a job that failed in every round is its first failure's row;
/// - when every round was `not_run` (each time its structure's child died in another job), the
///   first: the job stays `not_run`, and `suite --resume` runs it again.
#include <cstddef>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// The index in `rounds` (round k at k - 1) of the round whose result is kept. `rounds` holds
/// each round's complete result (or status row) and is not empty.
std::size_t kept_round(const std::vector<nlohmann::json>& rounds);

/// The job's result: the kept round's, with
///   "rounds": {"count": N, "kept": K (1-based),
///              "by_round": [{"round": k, "status": ..., "message": ...,
///                            "throughput_qps": {"median", "min", "max", "samples"} | null}, ...]}
/// (throughput null for a round that did not end ok). `rounds` as for kept_round().
nlohmann::json merge_rounds(const std::vector<nlohmann::json>& rounds);

}  // namespace bvhbench
