#pragma once
/// Which jobs of a suite share one structure, and so one child process and one build
/// (ARCHITECTURE.md, "Measurement protocol"): the same mesh, the same method with the same
/// options, the same threads; narrowed by what the method declares (registry.hpp:
/// StructureSharing): the same query type when its build reads the query type, each job alone
/// when its build reads the query points or its queries leave state a later job would inherit.
///
/// "The same options" are its build options alone for a method that takes query options after
/// its build (Capabilities::query_options_after_build: the EBP-Octree in memory, CGAL, Embree):
/// `coherent=true` asks the structure of the plain configuration another way, so both share one
/// build. Every other method is created with all of its options, each configuration a structure.
#include <cstddef>
#include <string>
#include <vector>

#include "harness/run/suite.hpp"

namespace bvhbench {

struct BuildGroup {
  std::string id;                 ///< file-system safe; the build.id of its results
  std::vector<std::size_t> jobs;  ///< indexes into the job list, in its order
};

/// The group id of a job: "MESH__METHOD[-k=v,..][__tT][__QUERY]" (k=v: structure_key), or the job's id when it builds
/// alone (and for a method this build does not know).
std::string build_group_id(const JobPlan& job);

/// `jobs` grouped by structure: groups in the order of their first job, each group's jobs in
/// the order of `jobs`.
std::vector<BuildGroup> group_by_structure(const std::vector<JobPlan>& jobs);

}  // namespace bvhbench
