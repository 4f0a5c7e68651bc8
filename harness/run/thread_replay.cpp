#include "harness/run/thread_replay.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <string>

#include "harness/run/counted_region.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

using Clock = std::chrono::steady_clock;

std::vector<ThreadStream> split_streams(const std::vector<Vec3d>& points, int threads) {
  std::vector<ThreadStream> out(std::size_t(std::max(1, threads)));
  const std::size_t n = points.size(), t = out.size();
  std::size_t start = 0;
  for (std::size_t k = 0; k < t; ++k) {
    const std::size_t len = n / t + (k < n % t ? 1 : 0);
    out[k] = {points.data() + start, len, start};
    start += len;
  }
  return out;
}

std::vector<ThreadStream> probe_streams(const std::vector<std::vector<Vec3d>>& paths) {
  std::vector<ThreadStream> out;
  std::size_t offset = 0;
  for (const auto& p : paths) {
    out.push_back({p.data(), p.size(), offset});
    offset += p.size();
  }
  return out;
}

namespace {

/// Keeps the compiler from discarding query results in timed loops: one per thread, read once.
struct Sink {
  double acc = 0;
  void take(bool b) { acc += b ? 1.0 : 0.0; }
  void take(const DistanceResult& d) { acc += d.distance + double(d.triangle); }
};
volatile double g_sink;

/// Replays `s` through `q`: `each(i, answer)` for the i-th query of the stream (`each` takes a
/// bool and a DistanceResult alike).
template <class Each>
void replay(QueryState& q, QueryType type, const ThreadStream& s, Each&& each) {
  if (type == QueryType::inside) {
    for (std::size_t i = 0; i < s.n; ++i) each(i, q.inside(s.points[i]));
  } else {
    for (std::size_t i = 0; i < s.n; ++i) each(i, q.distance(s.points[i]));
  }
}

}  // namespace

ThreadedReplay::ThreadedReplay(Method& method, QueryType type, std::vector<ThreadStream> streams)
    : method_(method),
      type_(type),
      streams_(std::move(streams)),
      team_(int(std::max<std::size_t>(1, streams_.size()))) {
  if (streams_.empty()) streams_.push_back({});
  for (const auto& s : streams_) total_ = std::max(total_, s.offset + s.n);
  owned_.resize(streams_.size());
  states_.assign(streams_.size(), &method_);
  if (streams_.size() == 1) return;
  // Made one at a time (new_query_state need not be safe to call concurrently), each on the
  // thread that will use it.
  std::mutex one_at_a_time;
  team_.run([&](int k) {
    if (k == 0) return;
    std::lock_guard<std::mutex> lock(one_at_a_time);
    owned_[std::size_t(k)] = method_.new_query_state();
  });
  for (std::size_t k = 1; k < owned_.size(); ++k) {
    if (!owned_[k])
      throw UnsupportedError("its queries may not run concurrently (no per-thread query state): threads must be 1");
    states_[k] = owned_[k].get();
  }
}

void ThreadedReplay::reset_paths() {
  team_.run([&](int k) { states_[std::size_t(k)]->reset_path(); });
}

void ThreadedReplay::counted_pass(Answers* out) {
  out->resize(type_, total_);
  team_.run([&](int k) {
    QueryState& q = *states_[std::size_t(k)];
    const ThreadStream& s = streams_[std::size_t(k)];
    q.reset_counters();
    q.reset_path();
    if (type_ == QueryType::inside) {
      for (std::size_t i = 0; i < s.n; ++i) out->inside[s.offset + i] = q.inside(s.points[i]) ? 1 : 0;
    } else {
      for (std::size_t i = 0; i < s.n; ++i) {
        const DistanceResult d = q.distance(s.points[i]);
        const std::size_t j = s.offset + i;
        out->distance[j] = d.distance;
        out->closest[j] = d.closest;
        out->normal[j] = d.normal;
        out->triangle[j] = d.triangle;
      }
    }
  });
}

std::vector<Counter> ThreadedReplay::counters() const {
  std::vector<Counter> sum = states_[0]->counters();
  std::map<std::string, std::size_t> at;
  for (std::size_t i = 0; i < sum.size(); ++i) at[sum[i].name] = i;
  for (std::size_t k = 1; k < states_.size(); ++k)
    for (const Counter& c : states_[k]->counters()) {
      auto it = at.find(c.name);
      if (it == at.end()) {
        at[c.name] = sum.size();
        sum.push_back(c);
      } else {
        sum[it->second].value += c.value;
      }
    }
  return sum;
}

double ThreadedReplay::timed_pass() {
  reset_paths();
  std::vector<double> sinks(streams_.size());
  const CountedRegion counted;  // the instruction gate counts this pass (counted_region.hpp)
  const double seconds = team_.run([&](int k) {
    Sink sink;
    replay(*states_[std::size_t(k)], type_, streams_[std::size_t(k)], [&](std::size_t, const auto& a) { sink.take(a); });
    sinks[std::size_t(k)] = sink.acc;  // once per pass: no sharing in the loop
  });
  double acc = 0;
  for (double s : sinks) acc += s;
  g_sink = acc;
  return seconds;
}

double ThreadedReplay::single_thread_pass(const ThreadStream& stream) {
  method_.reset_path();
  Sink sink;
  const auto t0 = Clock::now();
  replay(method_, type_, stream, [&](std::size_t, const auto& a) { sink.take(a); });
  const auto t1 = Clock::now();
  g_sink = sink.acc;
  return std::chrono::duration<double>(t1 - t0).count();
}

void ThreadedReplay::latency_pass(std::vector<double>* ns) {
  ns->assign(total_, 0.0);
  reset_paths();
  std::vector<double> sinks(streams_.size());
  team_.run([&](int k) {
    QueryState& q = *states_[std::size_t(k)];
    const ThreadStream& s = streams_[std::size_t(k)];
    double* lat = ns->data() + s.offset;
    Sink sink;
    if (type_ == QueryType::inside) {
      for (std::size_t i = 0; i < s.n; ++i) {
        const auto t0 = Clock::now();
        sink.take(q.inside(s.points[i]));
        lat[i] = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
      }
    } else {
      for (std::size_t i = 0; i < s.n; ++i) {
        const auto t0 = Clock::now();
        sink.take(q.distance(s.points[i]));
        lat[i] = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
      }
    }
    sinks[std::size_t(k)] = sink.acc;
  });
  double acc = 0;
  for (double s : sinks) acc += s;
  g_sink = acc;
}

}  // namespace bvhbench
