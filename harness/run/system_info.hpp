#pragma once
/// The run's context block: the machine, the build, the library versions, the commit.
#include <string>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// The result's `context` block: date, host, CPU model, cores, compiler and flags, build type,
/// library versions, git commit and dirty flag.
nlohmann::json run_context();

std::string iso8601_now();

}  // namespace bvhbench
