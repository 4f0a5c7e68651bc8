// Latencies grouped by the query's distance to the surface (latency_by_distance.hpp).
#include "harness/run/latency_by_distance.hpp"

#include <algorithm>
#include <cmath>

#include "harness/io/npz.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

std::vector<double> distance_bin_edges() {
  std::vector<double> e;
  for (int k = -14; k <= 0; ++k) e.push_back(std::pow(10.0, 0.5 * k));
  return e;
}

DistanceBins bin_by_distance(const double* distance, const double* latency_ns, std::size_t n, double diagonal) {
  DistanceBins b;
  b.edges = distance_bin_edges();
  b.count.assign(b.edges.size() + 1, 0);
  b.latency_ns_sum.assign(b.edges.size() + 1, 0.0);
  std::vector<std::vector<double>> in_bin(b.edges.size() + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const double rel = std::abs(distance[i]) / diagonal;
    if (!std::isfinite(rel)) continue;
    // The first edge above rel is the bin's upper end: bin i is [edges[i-1], edges[i]).
    const std::size_t bin = std::size_t(std::upper_bound(b.edges.begin(), b.edges.end(), rel) - b.edges.begin());
    ++b.count[bin];
    b.latency_ns_sum[bin] += latency_ns[i];
    in_bin[bin].push_back(latency_ns[i]);
  }
  b.latency_ns_p50.assign(b.edges.size() + 1, 0.0);
  for (std::size_t k = 0; k < in_bin.size(); ++k) {
    std::vector<double>& v = in_bin[k];
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    const std::size_t h = v.size() / 2;
    b.latency_ns_p50[k] = v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
  }
  return b;
}

nlohmann::json latency_by_distance(const std::vector<double>& latency_ns, const std::string& truth_path,
                                   double diagonal) {
  const auto t = read_npz(truth_path);
  const auto it = t.find("distance");
  if (it == t.end()) throw file_error(truth_path, "oracle has no 'distance' array (is it a bvhbench truth file?)");
  const NpyArray& d = it->second;
  if (d.dtype != "<f8" || d.size() != latency_ns.size())
    throw file_error(truth_path, "oracle 'distance' has " + std::to_string(d.size()) + " values of dtype " + d.dtype +
                                     ", expected " + std::to_string(latency_ns.size()) + " of <f8");
  const DistanceBins b = bin_by_distance(d.as<double>(), latency_ns.data(), latency_ns.size(), diagonal);
  return {{"edges", b.edges},
          {"count", b.count},
          {"latency_ns_sum", b.latency_ns_sum},
          {"latency_ns_p50", b.latency_ns_p50}};
}

}  // namespace bvhbench
