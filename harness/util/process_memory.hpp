#pragma once
/// The process's memory as the kernel counts it (/proc/self/status), for the measurement
/// protocol's peak and query-time RSS.
#include <cstddef>

namespace bvhbench {

std::size_t current_rss_bytes();  ///< VmRSS
std::size_t peak_rss_bytes();     ///< VmHWM (since start or the last reset)
/// Resets the kernel's peak-RSS mark to the current RSS (writes 5 to /proc/self/clear_refs).
/// Returns false where the kernel does not allow it (then peaks are since process start).
bool reset_peak_rss();

}  // namespace bvhbench
