// The Mann-Whitney U test (mann_whitney.hpp), its exact and asymptotic p-values as scipy's.
#include "harness/run/mann_whitney.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace bvhbench {

namespace {

/// Mid-ranks (1-based) of the pooled sample, and the tie groups' sizes.
std::vector<double> midranks(const std::vector<double>& pooled, std::vector<std::size_t>* ties) {
  const std::size_t n = pooled.size();
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return pooled[a] < pooled[b]; });
  std::vector<double> rank(n);
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i;
    while (j + 1 < n && pooled[order[j + 1]] == pooled[order[i]]) ++j;
    const double r = 0.5 * double(i + 1 + j + 1);
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = r;
    if (ties) ties->push_back(j - i + 1);
    i = j + 1;
  }
  return rank;
}

}  // namespace

MannWhitney mann_whitney_u(const std::vector<double>& x, const std::vector<double>& y, bool force_exact,
                           bool force_asymptotic) {
  MannWhitney r;
  const std::size_t n1 = x.size(), n2 = y.size(), n = n1 + n2;
  if (n1 == 0 || n2 == 0) return r;
  std::vector<double> pooled(x);
  pooled.insert(pooled.end(), y.begin(), y.end());
  std::vector<std::size_t> ties;
  const std::vector<double> rank = midranks(pooled, &ties);
  double r1 = 0;
  for (std::size_t i = 0; i < n1; ++i) r1 += rank[i];
  r.u1 = r1 - double(n1) * double(n1 + 1) / 2;
  const double u2 = double(n1) * double(n2) - r.u1;
  r.u = std::max(r.u1, u2);

  const bool exact = force_exact || (!force_asymptotic && n1 <= kMannWhitneyExactMax && n2 <= kMannWhitneyExactMax);
  if (exact) {
    // Permutation distribution of the first sample's rank sum: count the n1-subsets of the
    // pooled ranks by their sum. Ranks are doubled so that mid-ranks (k + 1/2) are integers.
    std::vector<long> r2(n);
    long total2 = 0;
    for (std::size_t i = 0; i < n; ++i) total2 += (r2[i] = std::lround(2 * rank[i]));
    const long obs2 = std::lround(2 * r1);
    // ways[k][s]: number of k-subsets of the ranks seen so far with doubled sum s.
    std::vector<std::vector<long double>> ways(n1 + 1, std::vector<long double>(std::size_t(total2) + 1, 0.0L));
    ways[0][0] = 1;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = std::min(i + 1, n1); k >= 1; --k)
        for (long s = total2; s >= r2[i]; --s) ways[k][std::size_t(s)] += ways[k - 1][std::size_t(s - r2[i])];
    long double all = 0, le = 0, ge = 0;
    for (long s = 0; s <= total2; ++s) {
      const long double w = ways[n1][std::size_t(s)];
      all += w;
      if (s <= obs2) le += w;
      if (s >= obs2) ge += w;
    }
    r.p_value = double(std::min<long double>(1.0L, 2.0L * std::min(le, ge) / all));
    r.exact = true;
  } else {
    double tie_term = 0;
    for (std::size_t t : ties) tie_term += double(t) * double(t) * double(t) - double(t);
    const double nn = double(n);
    const double var = double(n1) * double(n2) / 12.0 * ((nn + 1) - tie_term / (nn * (nn - 1)));
    if (var <= 0) {
      r.p_value = 1;  // every value equal: nothing to tell apart
    } else {
      const double z = (r.u - double(n1) * double(n2) / 2 - 0.5) / std::sqrt(var);
      r.p_value = std::min(1.0, std::max(0.0, std::erfc(z / std::sqrt(2.0))));
    }
    r.exact = false;
  }
  return r;
}

}  // namespace bvhbench
