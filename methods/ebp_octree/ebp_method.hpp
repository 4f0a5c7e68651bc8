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

/// The method's parameters: the build options (build_option_params.hpp), the query options
/// (coherence) and the out-of-core store's (ooc_method.hpp).
std::vector<ParamSpec> ebp_params();

/// The options of `ebp build` / `ebp stats` (`--param k=v`, parsed), resolved against the
/// method's declaration: only build options (kBuildOptions) may be given; another option of the
/// method is InputError "--param K: not a build option (build options: ...)".
Params resolve_build_args(const std::map<std::string, std::string>& given);

/// build_octree over the mesh, reporting to `external` (or, if null, to a progress line of its
/// own for meshes over 200k triangles). Throws InputError naming the mesh on bad geometry.
ebp::Octree build_tree(const Mesh& mesh, const ebp::BuildParams& bp, Progress* external);

/// The tree's figures (`ebp stats --json`, the method's info in a result file).
nlohmann::json stats_json(const ebp::Octree& t);

}  // namespace bvhbench
