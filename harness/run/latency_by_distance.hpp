#pragma once
/// A job's per-query latencies grouped by how far each query point lies from the surface, so
/// that the report can show where a method is fast and where it is slow (a distance search is
/// cheap in contact and dear far away; a ray parity test the other way round). The distance is
/// the oracle's |d| (`bvhbench truth`), relative to the mesh's bounding-box diagonal, in fixed
/// half-decade bins: the same bins in every result, so that jobs and models line up.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// Per-bin count, summed latency and median latency (0 for an empty bin; the median of an even
/// count is the mean of the middle two). Bin 0 holds |d| / diagonal below edges[0], bin i
/// (0 < i < edges.size()) holds edges[i-1] <= |d| / diagonal < edges[i], the last bin holds the
/// rest: count, latency_ns_sum and latency_ns_p50 have edges.size() + 1 entries. The median is
/// what a chart should read on a shared machine: one query preempted for a millisecond moves a
/// bin's mean, not its median.
struct DistanceBins {
  std::vector<double> edges;
  std::vector<long long> count;
  std::vector<double> latency_ns_sum;
  std::vector<double> latency_ns_p50;
};

/// The fixed inner edges: 10^-7 to 10^0 by half decades (15 edges, 16 bins).
std::vector<double> distance_bin_edges();

/// Bins queries by distance. `distance` (the oracle's |d|, any sign taken as magnitude) and
/// `latency_ns` hold n values each, query by query in the same order; `diagonal` > 0. A query
/// whose distance is not finite is left out.
DistanceBins bin_by_distance(const double* distance, const double* latency_ns, std::size_t n, double diagonal);

/// The result's `queries.by_distance` block (docs/results.md) from the latency pass's
/// latencies in query order (n = the query set's size) and the oracle file, which must hold a
/// `distance` array of n values (InputError otherwise).
nlohmann::json latency_by_distance(const std::vector<double>& latency_ns, const std::string& truth_path,
                                   double diagonal);

}  // namespace bvhbench
