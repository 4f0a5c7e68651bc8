// Query sets: the registered kinds (query_kinds*.cpp) and their generation.
#include "harness/core/query_set.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "harness/core/mesh.hpp"
#include "harness/core/triangle_source.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/nearest_word.hpp"

namespace bvhbench {

Box3d QuerySet::bounds() const {
  Box3d b;
  for (auto& p : points) b.add(p);
  return b;
}

// ---------------------------------------------------------------------------------------------

Params query_kind_params(const QueryKind& kind, const std::map<std::string, std::string>& given) {
  return Params::resolve_for("query kind '" + kind.name + "'", kind.params, given);
}

Params query_kind_params(const QueryKind& kind, const std::map<std::string, double>& given) {
  // Through the same check as text: the shortest text that reads back to each double (exact).
  std::map<std::string, std::string> text;
  for (const auto& [key, v] : given) {
    ParamValue number;
    number.type = ParamType::real;
    number.real = v;
    text[key] = number.canonical();
  }
  return query_kind_params(kind, text);
}

std::map<std::string, double> query_param_values(const QueryKind& kind, const Params& params) {
  std::map<std::string, double> out;
  for (const ParamSpec& p : kind.params) out[p.name] = params.get_real(p.name);
  return out;
}

const QueryKind& query_kind(const std::string& name) {
  if (const QueryKind* k = find_query_kind(name)) return *k;
  std::string known;
  std::vector<std::string> names;
  for (auto& q : query_kinds()) {
    known += (known.empty() ? "" : ", ") + q.name;
    names.push_back(q.name);
  }
  const std::string nearest = nearest_word(name, names);
  throw InputError("unknown query kind '" + name + "' (" + (nearest.empty() ? "" : "did you mean '" + nearest + "'? ") +
                   "known: " + known + ")");
}

namespace {

/// The sidecar of a generated set (query_set_io.hpp writes it beside the points).
nlohmann::json sidecar(const MeshSummary& mesh, const QueryKind& k, std::size_t n, std::uint64_t seed,
                       const Params& params) {
  nlohmann::json m;
  m["kind"] = k.name;
  m["n"] = n;
  m["seed"] = seed;
  m["mesh_sha256"] = mesh.sha256;
  m["mesh_path"] = mesh.path;
  m["mesh_triangles"] = mesh.triangles;
  m["ordered"] = k.ordered;
  m["params"] = query_param_values(k, params);
  m["created_by"] = "bvhbench queries";
  return m;
}

}  // namespace

std::vector<Vec3d> generate_queries(const Mesh& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed,
                                    const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta) {
  return generate_queries(MeshTriangles(mesh), kind, n, seed, given_params, meta);
}

std::vector<Vec3d> generate_queries(const TriangleSource& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed, const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta) {
  const QueryKind& k = query_kind(kind);
  const Params params = query_kind_params(k, given_params);
  auto pts = k.generate(mesh, n, seed, params);
  if (meta) *meta = sidecar(mesh.summary(), k, pts.size(), seed, params);
  return pts;
}

std::vector<Vec3d> generate_queries(const MeshSummary& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed, const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta) {
  const QueryKind& k = query_kind(kind);
  if (!k.generate_in_box) throw std::logic_error("query kind '" + kind + "' needs the mesh, not its summary");
  const Params params = query_kind_params(k, given_params);
  auto pts = k.generate_in_box(mesh.bounds, n, seed, params);
  if (meta) *meta = sidecar(mesh, k, pts.size(), seed, params);
  return pts;
}

bool replays_as_probes(const QuerySet& qs) {
  const QueryKind* k = find_query_kind(qs.kind());
  return k && k->ordered && qs.meta.contains("seed") && qs.meta["seed"].is_number_unsigned();
}

std::uint64_t probe_seed(std::uint64_t seed, int k) {
  if (k == 0) return seed;
  // splitmix64's finaliser over (seed, k): consecutive k land far apart, and no k >= 1 gives
  // back `seed` itself or a small neighbour of it (which a suite may use for another set).
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ull * std::uint64_t(k);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

std::vector<std::vector<Vec3d>> probe_paths(const Mesh& mesh, const QuerySet& qs, int probes) {
  std::vector<std::vector<Vec3d>> paths;
  paths.reserve(std::size_t(std::max(1, probes)));
  paths.push_back(qs.points);
  if (probes <= 1) return paths;
  const std::uint64_t seed = qs.meta.at("seed").get<std::uint64_t>();
  std::map<std::string, double> params;
  if (qs.meta.contains("params") && qs.meta["params"].is_object())
    for (auto& [key, v] : qs.meta["params"].items()) {
      if (!v.is_number()) throw InputError(qs.path + ": sidecar parameter '" + key + "' is not a number");
      params[key] = v.get<double>();
    }
  for (int k = 1; k < probes; ++k)
    paths.push_back(generate_queries(mesh, qs.kind(), qs.points.size(), probe_seed(seed, k), params, nullptr));
  return paths;
}

const QueryKind* find_query_kind(const std::string& name) {
  for (auto& k : query_kinds())
    if (k.name == name) return &k;
  return nullptr;
}

}  // namespace bvhbench
