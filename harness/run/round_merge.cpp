// The best of a job's rounds, and the record of them all (round_merge.hpp).
#include "harness/run/round_merge.hpp"

#include <limits>
#include <optional>
#include <string>
#include <stdexcept>

#include "harness/run/run_job.hpp"
#include "harness/util/json_path.hpp"

using json = nlohmann::json;

namespace bvhbench {

namespace {

std::string status_of(const json& r) { return r.is_object() ? r.value("status", std::string()) : std::string(); }

/// The median throughput of a round, or -infinity when it has none.
double median_qps(const json& r) {
  const json& m = json_at(r, {"queries", "throughput_qps", "median"});
  return m.is_number() ? m.get<double>() : -std::numeric_limits<double>::infinity();
}

}  // namespace

std::size_t kept_round(const std::vector<json>& rounds) {
  if (rounds.empty()) throw std::logic_error("kept_round: no rounds");
  std::optional<std::size_t> best;
  for (std::size_t k = 0; k < rounds.size(); ++k)
    if (status_of(rounds[k]) == status::ok && (!best || median_qps(rounds[k]) > median_qps(rounds[*best]))) best = k;
  if (best) return *best;
  for (std::size_t k = 0; k < rounds.size(); ++k)
    if (status_of(rounds[k]) != status::not_run) return k;
  return 0;
}

json merge_rounds(const std::vector<json>& rounds) {
  const std::size_t kept = kept_round(rounds);
  json by_round = json::array();
  for (std::size_t k = 0; k < rounds.size(); ++k) {
    const json& r = rounds[k];
    const json& qps = json_at(r, {"queries", "throughput_qps"});
    const bool ok = status_of(r) == status::ok && qps.is_object();
    by_round.push_back({{"round", k + 1},
                        {"status", status_of(r)},
                        {"message", r.is_object() ? r.value("message", std::string()) : std::string()},
                        {"throughput_qps", ok ? qps : json(nullptr)}});
  }
  json merged = rounds[kept];
  merged["rounds"] = {{"count", rounds.size()}, {"kept", kept + 1}, {"by_round", std::move(by_round)}};
  return merged;
}

}  // namespace bvhbench
