#include "harness/util/process_memory.hpp"

#include <fstream>
#include <string>

namespace bvhbench {

namespace {

std::size_t status_field_kb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  std::size_t n = std::char_traits<char>::length(key);
  while (std::getline(f, line)) {
    if (line.compare(0, n, key) == 0) return std::stoull(line.substr(n + 1)) * 1024;
  }
  return 0;
}

}  // namespace

std::size_t current_rss_bytes() { return status_field_kb("VmRSS:"); }
std::size_t peak_rss_bytes() { return status_field_kb("VmHWM:"); }

bool reset_peak_rss() {
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.flush();
  return bool(f);
}

}  // namespace bvhbench
