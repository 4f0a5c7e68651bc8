// The measurement protocol of a job's queries (query_protocol.hpp).
#include "harness/run/query_protocol.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "harness/run/counted_region.hpp"
#include "harness/util/process_memory.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

using Clock = std::chrono::steady_clock;

QueryProtocol::QueryProtocol(Method& method, QueryType type, const std::vector<Vec3d>& points,
                             std::vector<ThreadStream> streams, ThreadStream single)
    : method_(method),
      type_(type),
      points_(points),
      replay_(method, type, std::move(streams)),
      single_(single),
      batcher_(batch_answers(method)) {
  m_.total = replay_.total();
  m_.batch = batcher_ != nullptr;
}

void QueryProtocol::batch_call() {
  const std::size_t n = points_.size();
  if (type_ == QueryType::inside) {
    batch_inside_.assign(n, 0);
    batcher_->inside_batch(points_, batch_inside_);
    if (batch_inside_.size() != n)
      throw std::runtime_error("inside_batch gave " + std::to_string(batch_inside_.size()) + " answers for " +
                               std::to_string(n) + " points");
  } else {
    batch_distance_.assign(n, DistanceResult{});
    batcher_->distance_batch(points_, batch_distance_);
    if (batch_distance_.size() != n)
      throw std::runtime_error("distance_batch gave " + std::to_string(batch_distance_.size()) + " answers for " +
                               std::to_string(n) + " points");
  }
}

double QueryProtocol::timed_batch_pass() {
  method_.reset_path();
  const CountedRegion counted;  // the instruction gate counts this pass (counted_region.hpp)
  auto t0 = Clock::now();
  batch_call();  // the answers land in the buffers, so the call cannot be optimised away
  auto t1 = Clock::now();
  return std::chrono::duration<double>(t1 - t0).count();
}

void QueryProtocol::counted_pass(Answers* answers) {
  if (m_.batch) {
    // A batch method declares no concurrent queries: it runs on one thread (threads > 1 was
    // refused before building).
    const std::size_t n = points_.size();
    answers->resize(type_, n);
    method_.reset_counters();
    method_.reset_path();
    batch_call();
    if (type_ == QueryType::inside) {
      answers->inside = batch_inside_;
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        const DistanceResult& d = batch_distance_[i];
        answers->distance[i] = d.distance;
        answers->closest[i] = d.closest;
        answers->normal[i] = d.normal;
        answers->triangle[i] = d.triangle;
      }
    }
  } else {
    replay_.counted_pass(answers);
  }
  m_.counters = replay_.counters();
  m_.query_rss = current_rss_bytes();
}

void QueryProtocol::timed_passes(int repeat, Progress& progress) {
  const bool with_single = replay_.threads() > 1;
  for (int rep = 0; rep < repeat; ++rep) {
    const double s = m_.batch ? timed_batch_pass() : replay_.timed_pass();
    m_.pass_seconds.push_back(s);
    m_.qps.push_back(s > 0 ? double(m_.total) / s : 0.0);
    m_.query_rss = std::max(m_.query_rss, current_rss_bytes());
    if (with_single) {
      const double s1 = replay_.single_thread_pass(single_);
      m_.single_qps.push_back(s1 > 0 ? double(single_.n) / s1 : 0.0);
      progress.update(2 * rep + 2);
    } else {
      progress.update(rep + 1);
    }
  }
  // One call answers every query of a batch: no query has a latency of its own, so none is
  // recorded rather than the pass time spread evenly over the queries.
  if (!m_.batch) replay_.latency_pass(&m_.latency_in_order);
  m_.latency_ns = m_.latency_in_order;
  std::sort(m_.latency_ns.begin(), m_.latency_ns.end());
  m_.query_rss = std::max(m_.query_rss, current_rss_bytes());
}

}  // namespace bvhbench
