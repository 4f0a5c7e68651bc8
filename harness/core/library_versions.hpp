#pragma once
/// The versions of the libraries compiled into this build (CGAL, Embree, OpenVDB, ...), noted by
/// each method's registration, recorded in every result's context.
#include <map>
#include <string>

namespace bvhbench {

/// Notes `name` -> `version` (a later note of the same name replaces it).
void note_library_version(const std::string& name, const std::string& version);
/// Every version noted so far, by library name.
std::map<std::string, std::string> library_versions();

}  // namespace bvhbench
