#pragma once
/// What the in-memory ebp_octree method (ebp_method.cpp) shares with the `bvhbench ebp` commands:
/// its parameters, the build of a tree from a loaded mesh, and the tree's figures as JSON.
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/params.hpp"
#include "harness/util/progress.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace bvhbench {

/// The method's parameters (build, coherence, and the out-of-core store's).
std::vector<ParamSpec> ebp_params();

/// The options of `ebp build` / `ebp stats` (`--param k=v`, parsed), resolved against the
/// method's declaration: only build options (ParamRole::build, not `store`) may be given; another
/// is InputError "--param K: not a build option (build options: ...)".
Params resolve_build_args(const std::map<std::string, std::string>& given);

/// The build parameters among resolved method parameters `p`, with `threads` build threads.
ebp::BuildParams build_params(const Params& p, int threads);

/// Octree::build over the mesh, reporting to `external` (or, if null, to a progress line of its
/// own for meshes over 200k triangles). Throws InputError naming the mesh on bad geometry.
ebp::Octree build_tree(const Mesh& mesh, const ebp::BuildParams& bp, Progress* external);

/// The tree's figures (`ebp stats --json`, the method's info in a result file).
nlohmann::json stats_json(const ebp::Octree& t);

}  // namespace bvhbench
