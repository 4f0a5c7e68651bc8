#include "harness/core/library_versions.hpp"

namespace bvhbench {

namespace {

std::map<std::string, std::string>& versions() {
  static std::map<std::string, std::string> m;
  return m;
}

}  // namespace

void note_library_version(const std::string& name, const std::string& version) { versions()[name] = version; }

std::map<std::string, std::string> library_versions() { return versions(); }

}  // namespace bvhbench
