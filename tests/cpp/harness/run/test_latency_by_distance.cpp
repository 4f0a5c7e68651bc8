// Latencies grouped by the query's distance to the surface (run/latency_by_distance.hpp): which
// bin a distance falls in, at and between the edges, and what each bin sums.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "harness/run/latency_by_distance.hpp"

using namespace bvhbench;

TEST(LatencyByDistance, EdgesAreHalfDecadesFromTenToTheMinusSevenToOne) {
  const std::vector<double> e = distance_bin_edges();
  ASSERT_EQ(e.size(), 15u);
  EXPECT_DOUBLE_EQ(e.front(), 1e-7);
  EXPECT_DOUBLE_EQ(e.back(), 1.0);
  for (std::size_t i = 1; i < e.size(); ++i) EXPECT_NEAR(e[i] / e[i - 1], std::sqrt(10.0), 1e-12);
}

TEST(LatencyByDistance, EachQueryLandsInTheBinOfItsRelativeDistance) {
  const double diagonal = 2.0;
  const std::vector<double> e = distance_bin_edges();
  // On the surface, just under the first edge, exactly on an edge (the bin above it), between
  // two edges, a negative (inside) distance, beyond the last edge, and a NaN (left out).
  const std::vector<double> d = {0.0, 0.5e-7 * diagonal, e[3] * diagonal, 2e-5 * diagonal, -2e-5 * diagonal,
                                 3.0 * diagonal, std::numeric_limits<double>::quiet_NaN()};
  const std::vector<double> lat = {10, 20, 30, 40, 50, 60, 70};
  const DistanceBins b = bin_by_distance(d.data(), lat.data(), d.size(), diagonal);
  ASSERT_EQ(b.count.size(), e.size() + 1);
  ASSERT_EQ(b.latency_ns_sum.size(), e.size() + 1);
  std::vector<long long> want(e.size() + 1, 0);
  std::vector<double> want_sum(e.size() + 1, 0.0);
  want[0] = 2, want_sum[0] = 30;        // 0 and 0.5e-7: below the first edge
  want[4] = 1, want_sum[4] = 30;        // on e[3]: [e[3], e[4])
  want[5] = 2, want_sum[5] = 90;        // 2e-5 in [10^-4.5, 10^-4), either sign
  want[e.size()] = 1, want_sum[e.size()] = 60;  // beyond 1
  EXPECT_EQ(b.count, want);
  EXPECT_EQ(b.latency_ns_sum, want_sum);
  std::vector<double> want_p50(e.size() + 1, 0.0);
  want_p50[0] = 15, want_p50[4] = 30, want_p50[5] = 45, want_p50[e.size()] = 60;
  EXPECT_EQ(b.latency_ns_p50, want_p50);
}

TEST(LatencyByDistance, AMedianIsNotMovedByOneSlowQuery) {
  const std::vector<double> d = {1.5e-3, 1.5e-3, 1.5e-3};
  const std::vector<double> lat = {100, 1e6, 120};
  const DistanceBins b = bin_by_distance(d.data(), lat.data(), d.size(), 1.0);
  const std::size_t bin = 9;  // [edges[8], edges[9]) = [1e-3, 10^-2.5)
  ASSERT_EQ(b.count[bin], 3);
  EXPECT_EQ(b.latency_ns_p50[bin], 120);
}
