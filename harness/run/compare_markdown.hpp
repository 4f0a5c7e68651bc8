#pragma once
/// compare's report for people: the verdicts of compare_result_sets() as Markdown (what CI prints).
#include <string>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// A readable Markdown report of compare_result_sets()'s JSON.
std::string compare_markdown(const nlohmann::json& report);

}  // namespace bvhbench
