#pragma once
/// The query passes of one job on T threads (run_job.cpp's measurement protocol): each thread
/// replays its own stream of queries through its own query state (method.hpp: QueryState) over
/// the method's one built structure. Thread 0 asks the method itself, so T = 1 is exactly the
/// single-threaded replay, on the calling thread.
///
/// Two ways a query set becomes T streams (docs/results.md, "Threads"):
///  - split: unordered points (random, near, surface) and points files are cut into T
///    contiguous parts of nearly equal size; each thread replays its part in order;
///  - probes: a generated path (haptic) stays whole, and each thread replays its own path of the
///    same kind and length, seeded apart (probe_paths), as T haptic devices would.
#include <cstddef>
#include <memory>
#include <vector>

#include "harness/core/method.hpp"
#include "harness/run/accuracy.hpp"
#include "harness/run/thread_team.hpp"

namespace bvhbench {

/// One thread's queries: `n` points from `points`, replayed in order. Its answers (and latencies)
/// go to [offset, offset + n) of the job's, where the threads' answers lie side by side.
struct ThreadStream {
  const Vec3d* points = nullptr;
  std::size_t n = 0;
  std::size_t offset = 0;
};

/// `points` cut into `threads` contiguous parts, in order (the first n % threads one longer); a
/// part may be empty when there are fewer points than threads. Offsets are the parts' places in
/// `points`, so the answers come back in the query set's order.
std::vector<ThreadStream> split_streams(const std::vector<Vec3d>& points, int threads);

/// Thread k replays paths[k] whole; offsets k x n for paths of n points each, so path 0's answers
/// come first. The paths must outlive the streams.
std::vector<ThreadStream> probe_streams(const std::vector<std::vector<Vec3d>>& paths);

class ThreadedReplay {
 public:
  /// One thread per stream (at least one stream). Makes the query states: thread 0 asks `method`
  /// itself, thread k >= 1 a state from method.new_query_state(), made on thread k (so that what
  /// it allocates is that thread's). Throws UnsupportedError when the method hands out none.
  /// `method` must be built, and outlive this.
  ThreadedReplay(Method& method, QueryType type, std::vector<ThreadStream> streams);

  int threads() const { return team_.size(); }
  /// Queries per pass, over all threads.
  std::size_t total() const { return total_; }

  /// The counted pass: every state's counters and path reset, then every answer recorded into
  /// `out` (resized to total()).
  void counted_pass(Answers* out);
  /// The counters of the counted pass, summed over the threads (thread 0's names and order).
  std::vector<Counter> counters() const;

  /// A timed pass over all threads (paths reset first, untimed): its wall time in seconds.
  double timed_pass();
  /// The same pass on the calling thread alone, through the method itself: `stream` (a whole
  /// query set or one probe path) in order. The reference of the speed-up against one thread.
  double single_thread_pass(const ThreadStream& stream);
  /// A pass with per-query timestamps on all threads: `ns` (resized to total()) gets each
  /// query's latency in nanoseconds, in answer order.
  void latency_pass(std::vector<double>* ns);

 private:
  void reset_paths();
  Method& method_;
  QueryType type_;
  std::vector<ThreadStream> streams_;
  std::size_t total_ = 0;
  ThreadTeam team_;
  std::vector<std::unique_ptr<QueryState>> owned_;  // by thread; [0] empty (the method's own)
  std::vector<QueryState*> states_;                 // by thread
};

}  // namespace bvhbench
