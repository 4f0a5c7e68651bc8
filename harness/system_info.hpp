#pragma once
/// Facts about the process and the machine: memory (RSS), the run's context block.
#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

namespace bvhbench {

std::size_t current_rss_bytes();  ///< VmRSS
std::size_t peak_rss_bytes();     ///< VmHWM (since start or the last reset)
/// Resets the kernel's peak-RSS mark to the current RSS (writes 5 to /proc/self/clear_refs).
/// Returns false where the kernel does not allow it (then peaks are since process start).
bool reset_peak_rss();

/// The result's `context` block: date, host, CPU model, cores, compiler and flags, build type,
/// library versions, git commit and dirty flag.
nlohmann::json run_context();

/// Library versions compiled in, filled by each method's registration (name -> version).
void note_library_version(const std::string& name, const std::string& version);

std::string iso8601_now();

}  // namespace bvhbench
