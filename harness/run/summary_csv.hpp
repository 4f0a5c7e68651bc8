#pragma once
/// `summary.csv`: one flat row per result of a suite, beside its runs/ folder (docs/results.md).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// The flat summary row of one result (also used by compare and tests).
std::vector<std::string> summary_header();
std::vector<std::string> summary_row(const nlohmann::json& result);
/// Writes summary.csv for these results atomically (AtomicOutputFile).
void write_summary_csv(const std::string& path, const std::vector<nlohmann::json>& results);

}  // namespace bvhbench
