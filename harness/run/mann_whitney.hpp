#pragma once
/// The two-sided Mann-Whitney U test with which `compare` decides whether throughput changed:
/// rank-based, so it assumes no distribution of the per-repetition samples (docs/compare.md).
#include <cstddef>
#include <vector>

namespace bvhbench {

struct MannWhitney {
  double u1 = 0;       ///< U statistic of the first sample: #{(i,j): x_i > y_j} + 0.5 #{x_i == y_j}
  double u = 0;        ///< max(U1, U2), the statistic scipy reports for two-sided tests
  double p_value = 1;  ///< two-sided; 1 when either sample is empty
  bool exact = false;  ///< exact permutation distribution (with ties: of the mid-rank sums)
};

/// Samples up to this size per side get the exact distribution, larger ones the normal
/// approximation (tie-corrected variance, continuity correction), as scipy.stats.mannwhitneyu.
inline constexpr std::size_t kMannWhitneyExactMax = 20;

/// Two-sided Mann-Whitney U test of H0 "x and y come from the same distribution".
/// Exact: p = min(1, 2 min(P(U1 <= u1), P(U1 >= u1))) under the permutation distribution of the
/// observed mid-ranks (equal to scipy's method="exact" when there are no ties).
/// Asymptotic: z = (max(U1,U2) - n1 n2 / 2 - 0.5) / sigma, p = 2 (1 - Phi(z)), with
/// sigma^2 = n1 n2 / 12 ((n + 1) - sum(t^3 - t) / (n (n - 1))) (scipy's method="asymptotic").
/// `force_exact` / `force_asymptotic` override the size rule (for tests).
MannWhitney mann_whitney_u(const std::vector<double>& x, const std::vector<double>& y,
                           bool force_exact = false, bool force_asymptotic = false);

}  // namespace bvhbench
