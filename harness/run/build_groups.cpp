#include "harness/run/build_groups.hpp"

#include <map>
#include <set>

#include "harness/core/registry.hpp"
#include "harness/util/sha256.hpp"

namespace bvhbench {

std::string build_group_id(const JobPlan& job) {
  const MethodSpec& m = job.method;
  if (!m.resolved()) return job.id;
  const StructureSharing sharing = m.info->sharing ? m.info->sharing(m.params) : StructureSharing::every_job;
  if (sharing == StructureSharing::job_alone) return job.id;
  const std::string key = structure_key(m);  // configurations that differ in how they ask share one
  std::string id = job.mesh.name + "__" + m.info->name + (key.empty() ? "" : "-" + key) +
                   (job.threads == 1 ? "" : "__t" + std::to_string(job.threads));
  if (sharing == StructureSharing::same_query_type) id += std::string("__") + to_string(job.query);
  id = file_safe(id);
  if (id.size() > 200) id = id.substr(0, 180) + "-" + sha256_hex(id.data(), id.size()).substr(0, 12);
  return id;
}

std::vector<BuildGroup> group_by_structure(const std::vector<JobPlan>& jobs) {
  std::vector<BuildGroup> groups;
  // The key is the id and the mesh's path: two meshes of one short name are two structures.
  std::map<std::string, std::size_t> index;
  std::set<std::string> ids;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const std::string id = build_group_id(jobs[i]);
    auto [it, fresh] = index.emplace(id + "\n" + jobs[i].mesh.path, groups.size());
    if (fresh) {
      // Ids name files: a second mesh of the same short name gets "-2", "-3", ...
      std::string unique = id;
      for (int n = 2; ids.count(unique); ++n) unique = id + "-" + std::to_string(n);
      ids.insert(unique);
      groups.push_back(BuildGroup{unique, {}});
    }
    groups[it->second].jobs.push_back(i);
  }
  return groups;
}

}  // namespace bvhbench
