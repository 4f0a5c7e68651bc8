// Query sets: the registered kinds (query_kinds*.cpp) and their generation.
#include "harness/core/query_set.hpp"

#include <cmath>

#include "harness/core/mesh.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

Box3d QuerySet::bounds() const {
  Box3d b;
  for (auto& p : points) b.add(p);
  return b;
}

// ---------------------------------------------------------------------------------------------

std::vector<Vec3d> generate_queries(const Mesh& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed,
                                    const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta) {
  const QueryKind* k = find_query_kind(kind);
  if (!k) {
    std::string known;
    for (auto& q : query_kinds()) known += (known.empty() ? "" : ", ") + q.name;
    throw InputError("unknown query kind '" + kind + "' (known: " + known + ")");
  }
  std::map<std::string, double> params = k->defaults;
  for (auto& [key, v] : given_params) {
    if (!params.count(key)) {
      std::string known;
      for (auto& [d, _] : k->defaults) known += (known.empty() ? "" : ", ") + d;
      throw InputError("query kind '" + kind + "': unknown parameter '" + key + "' (known: " +
                       (known.empty() ? "none" : known) + ")");
    }
    if (!std::isfinite(v)) throw InputError("query kind '" + kind + "': parameter " + key + " is not finite");
    params[key] = v;
  }
  auto pts = k->generate(mesh, n, seed, params);
  if (meta) {
    nlohmann::json m;
    m["kind"] = kind;
    m["n"] = pts.size();
    m["seed"] = seed;
    m["mesh_sha256"] = mesh.sha256;
    m["mesh_path"] = mesh.path;
    m["mesh_triangles"] = mesh.num_triangles();
    m["ordered"] = k->ordered;
    m["params"] = params;
    m["created_by"] = "bvhbench queries";
    *meta = m;
  }
  return pts;
}

const QueryKind* find_query_kind(const std::string& name) {
  for (auto& k : query_kinds())
    if (k.name == name) return &k;
  return nullptr;
}

}  // namespace bvhbench
