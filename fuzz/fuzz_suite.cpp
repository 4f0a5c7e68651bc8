// Fuzz target: the suite loader (harness/suite.hpp: parse_suite; yaml-cpp underneath), with the
// methods of this build registered.
//
// Beyond the contract (fuzz_contract.hpp), an accepted suite must hold what the runner relies on
// without further checks: at least one repetition, a positive time limit, a finite memory limit
// of at least 0 (0 = none; the child's address-space limit), at most kMaxSuiteJobs jobs, and
// unique job ids that are filesystem-safe (they name result files).
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>

#include "fuzz_contract.hpp"
#include "suite.hpp"

using namespace bvhbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz/suite.yml";
  const std::string text(fuzz::as_text(data, size));
  SuiteConfig cfg;
  if (!fuzz::accepts(name, [&] { cfg = parse_suite(text, name); })) return 0;
  fuzz::check(cfg.repeat >= 1, "repeat < 1");
  fuzz::check(cfg.timeout_s > 0, "timeout_s is not > 0");
  fuzz::check(cfg.memory_limit_mb >= 0 && std::isfinite(cfg.memory_limit_mb),
              "memory_limit_mb is no address-space limit: " + std::to_string(cfg.memory_limit_mb));
  fuzz::check(cfg.jobs.size() <= kMaxSuiteJobs, std::to_string(cfg.jobs.size()) + " jobs");
  std::set<std::string> ids;
  for (const JobPlan& j : cfg.jobs) {
    fuzz::check(ids.insert(j.id).second, "job id " + j.id + " twice");
    fuzz::check(!j.id.empty() && j.id.size() <= 200, "job id of " + std::to_string(j.id.size()) + " bytes");
    for (char c : j.id)
      fuzz::check(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '=' || c == '_',
                  "job id " + j.id + " is not filesystem-safe");
  }
  return 0;
}
