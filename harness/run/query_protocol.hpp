#pragma once
/// The measurement protocol of a job's queries (docs/results.md), apart from the result JSON
/// that run_job assembles from it: a counted warm-up pass (answers and work counters), `repeat`
/// timed passes on T threads (each followed, for T > 1, by a pass on one thread, so that the
/// speed-up compares passes taken together), and one pass with per-query timestamps. A method
/// that answers in batches (batch_answers.hpp) is timed per whole-set call instead, and has no
/// per-query latency.
#include <cstddef>
#include <vector>

#include "harness/core/batch_answers.hpp"
#include "harness/core/method.hpp"
#include "harness/run/accuracy.hpp"
#include "harness/run/thread_replay.hpp"

namespace bvhbench {

class Progress;

/// What the protocol measured.
struct QueryMeasurement {
  std::size_t total = 0;           ///< queries per pass, over all threads
  bool batch = false;              ///< answered in whole-set calls
  std::vector<Counter> counters;   ///< the counted pass's totals, summed over the threads
  std::vector<double> qps;         ///< per timed pass, over all threads
  std::vector<double> pass_seconds;
  std::vector<double> single_qps;  ///< T > 1: the one-thread pass after each timed pass
  std::vector<double> latency_ns;  ///< per query of the latency pass, sorted; empty in batches
  /// The same latencies in the order the queries were answered: every thread's stream at its
  /// offset, so the query set's queries come first, in query order (path 0 for probes).
  std::vector<double> latency_in_order;
  std::size_t query_rss = 0;       ///< the largest resident set seen while querying
};

class QueryProtocol {
 public:
  /// `points` the query set (what a batch call and the one-thread pass of a split set answer),
  /// `streams` what each of the T threads replays, `single` what the one-thread passes replay.
  QueryProtocol(Method& method, QueryType type, const std::vector<Vec3d>& points, std::vector<ThreadStream> streams,
                ThreadStream single);

  /// The counted warm-up pass: every thread's answers into `answers` (the query set's first),
  /// and the work counters.
  void counted_pass(Answers* answers);
  /// `repeat` timed passes (and the one-thread passes when T > 1), reporting to `progress`, then
  /// the latency pass (none in batches).
  void timed_passes(int repeat, Progress& progress);

  const QueryMeasurement& measured() const { return m_; }
  int threads() const { return replay_.threads(); }

 private:
  /// One call answering every point, checked for the count of answers it gave.
  void batch_call();
  /// One timed batch pass (path reset first, untimed): its wall time in seconds.
  double timed_batch_pass();

  Method& method_;
  QueryType type_;
  const std::vector<Vec3d>& points_;
  ThreadedReplay replay_;
  ThreadStream single_;
  BatchAnswers* batcher_;
  // Reused output buffers of the batch calls, so that a timed pass allocates nothing.
  std::vector<std::uint8_t> batch_inside_;
  std::vector<DistanceResult> batch_distance_;
  QueryMeasurement m_;
};

}  // namespace bvhbench
