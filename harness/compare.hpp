#pragma once
/// `bvhbench compare BASE NEW`: verdicts between a baseline and a new result set.
///
/// Jobs are paired by method, resolved parameters, mesh sha256, query-set sha256 and query type.
/// Per pair, deterministic work counters and accuracy are compared exactly (any change gates),
/// except the counters NEW declares machine-dependent (MethodInfo::machine_dependent_counters):
/// those gate exactly only when both results carry the same machine fingerprint, and are
/// otherwise reported without gating (with the fingerprint fields that differ); throughput is compared with a two-sided Mann-Whitney U test over the per-repetition samples,
/// each side first normalised by its own calibration kernel (calibration.hpp), and counts only
/// when the change also exceeds a relative threshold. See docs/compare.md.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------
// Result sets and the comparison
// ---------------------------------------------------------------------------------------------

/// Result files read from a folder (`DIR/runs/*.json`, else `DIR/*.json`) or one file.
struct ResultSet {
  std::string path;
  std::vector<std::string> files;          ///< one per result, same order
  std::vector<nlohmann::json> results;
};

/// Reads and validates a result set. Throws InputError (exit 2) for a missing or empty folder,
/// an unreadable file, malformed JSON, or a file that is not a bvhbench result.
ResultSet load_result_set(const std::string& path);
/// Parses and validates the text of one result file (`file` names it in messages), as
/// load_result_set does for each. Throws InputError: malformed JSON, not a bvhbench result.
nlohmann::json parse_result(const std::string& text, const std::string& file);

struct CompareOptions {
  double threshold = 0.10;   ///< relative throughput change that matters (0.10 = 10%)
  double alpha = 0.01;       ///< significance level of the Mann-Whitney test
  bool timing_gates = true;  ///< false (--timing report): timing verdicts are shown, never gate
  bool ignore_missing = false;  ///< jobs of BASE absent from NEW do not gate (partial runs)
  /// Relative tolerance for *floating* accuracy summaries (means, percentiles, rates) only;
  /// counters, counts and statuses are always exact. 1e-12 absorbs re-association of a sum of
  /// ~1e4 terms (n * eps ~ 1e-12) and is orders of magnitude below a single changed answer.
  double rtol = 1e-12;
};

/// The comparison as JSON (schema "bvhbench.compare/1"): options, both sets' provenance, one
/// entry per pair (verdict, reasons, whether it gates, counter/accuracy differences, timing
/// statistics; `machine_dependent` and `counters_not_gated` for counters reported, not gated), a
/// summary by verdict (with `not_gated`: jobs, counter values, changed ones, why) and
/// `exit_code` (0 nothing gates, 1 something does).
nlohmann::json compare_result_sets(const ResultSet& base, const ResultSet& fresh,
                                   const CompareOptions& opt);

/// Where two machine fingerprints (machine_fingerprint.hpp) differ: one text per differing leaf
/// ("isa.avx512f true -> false", "cpu.model 1 -> 17", "libraries.embree (none) -> \"3.13.5\""),
/// sorted by path; empty when they are equal.
std::vector<std::string> fingerprint_differences(const nlohmann::json& base, const nlohmann::json& fresh);

/// A readable Markdown report of compare_result_sets()'s JSON.
std::string compare_markdown(const nlohmann::json& report);

}  // namespace bvhbench
