#pragma once
/// `bvhbench compare BASE NEW`: verdicts between a baseline and a new result set.
///
/// Jobs are paired by method, resolved parameters, mesh sha256, query-set sha256 and query type.
/// Per pair, deterministic work counters and accuracy are compared exactly (any change gates),
/// except the counters NEW declares machine-dependent (MethodInfo::machine_dependent_counters):
/// those gate exactly only when both results carry the same machine fingerprint, and are
/// otherwise reported without gating (with the fingerprint fields that differ); throughput is compared with a two-sided Mann-Whitney U test over the per-repetition samples,
/// each side first normalised by its own calibration kernel (calibration.hpp), and counts only
/// when the change also exceeds a relative threshold (mann_whitney.hpp). See docs/compare.md.
/// The Markdown report of the verdicts: compare_markdown.hpp.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/run/result_set.hpp"

namespace bvhbench {

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

}  // namespace bvhbench
