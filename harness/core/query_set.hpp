#pragma once
/// Query sets (docs/architecture.md, "Contracts": query sets): NAME.npy (float64, N x 3) plus NAME.json with at
/// least kind, n, seed, mesh_sha256 and the generator's parameters. Generation is deterministic:
/// the same mesh, kind, n, seed and parameters give the same bytes on any machine.
///
/// Points made elsewhere are query sets too: a bare NAME.npy (float64 or float32, N x 3, either
/// byte order, C or Fortran order) or a text file NAME.xyz / NAME.csv (points_text.hpp), without a
/// sidecar, is a set of kind `file`, identified by the sha256 of its bytes and replayed in the
/// file's order. A NAME.json beside any of them is its sidecar and is checked.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/geometry.hpp"
#include "harness/core/params.hpp"

namespace bvhbench {

struct Mesh;
struct MeshSummary;
class TriangleSource;

struct QuerySet {
  std::string path;         ///< the .npy, .xyz or .csv
  std::string sha256;       ///< of the file's bytes
  nlohmann::json meta;      ///< the sidecar; without one {kind: file, n, format, ordered: true}
  std::vector<Vec3d> points;
  std::string kind() const { return meta.value("kind", std::string("unknown")); }
  Box3d bounds() const;
};

/// A kind of query set. Registered in query_kinds.cpp (one entry each).
struct QueryKind {
  std::string name;
  std::string description;
  /// Its generator's parameters, declared as a method's options are (real numbers with a
  /// default, a help line and a range; all recorded in the sidecar); user values override by key.
  std::vector<ParamSpec> params;
  /// Generates n points on `mesh` (in memory or paged: triangle_source.hpp) from `seed` with the
  /// resolved parameters.
  std::function<std::vector<Vec3d>(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& params)>
      generate;
  bool ordered = false;  ///< a path whose order matters (haptic)
  /// For a kind that needs only the mesh's box (random): its generator from the box, which
  /// `generate` is on mesh.bounds(), so that its sets are made from the mesh file's streamed
  /// summary without loading the mesh (generate_queries on a MeshSummary). Null otherwise.
  std::function<std::vector<Vec3d>(const Box3d& box, std::size_t n, std::uint64_t seed, const Params& params)>
      generate_in_box;
};

const std::vector<QueryKind>& query_kinds();

/// The kind's parameters: `given` (by name, as text: `--param`, a suite's `params:`) checked
/// against its declaration, the others at their defaults. Throws InputError "query kind 'K': ..."
/// for an unknown parameter (with the nearest declared one), a value that is not a finite number,
/// or out of its range.
Params query_kind_params(const QueryKind& kind, const std::map<std::string, std::string>& given);
/// The same for values given as numbers (a sidecar's, a test's).
Params query_kind_params(const QueryKind& kind, const std::map<std::string, double>& given);
/// Every parameter's value, by name, as numbers (what a sidecar records as `params`).
std::map<std::string, double> query_param_values(const QueryKind& kind, const Params& params);

/// Whether T threads replay `qs` as T independent probes (a path of a registered ordered kind,
/// such as haptic, made by the generator: its sidecar gives kind, seed and parameters), rather
/// than splitting its points between them.
bool replays_as_probes(const QuerySet& qs);

/// The seed of probe k when a path generated from `seed` is replayed by several probes: k = 0 is
/// the path itself (`seed`); every other probe's is seeded apart (splitmix64 of seed and k), the
/// same on every machine.
std::uint64_t probe_seed(std::uint64_t seed, int k);

/// The `probes` paths that many probes replay (replays_as_probes(qs)): path 0 is qs's own points,
/// path k the generator's path of the same kind, length and parameters from probe_seed(seed, k)
/// on `mesh`. Throws InputError when the sidecar cannot be regenerated (a kind or parameter this
/// build does not know).
std::vector<std::vector<Vec3d>> probe_paths(const Mesh& mesh, const QuerySet& qs, int probes);
const QueryKind* find_query_kind(const std::string& name);
/// find_query_kind, or InputError "unknown query kind 'K' (known: ...)" with the nearest one.
const QueryKind& query_kind(const std::string& name);

/// Generates a query set and its sidecar meta (kind, n, seed, mesh_sha256, mesh path, params,
/// ordered). Throws InputError for an unknown kind, or a parameter unknown or out of its range
/// (query_kind_params).
std::vector<Vec3d> generate_queries(const Mesh& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed,
                                    const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta);
/// The same on the mesh's triangles however they are held (a loaded mesh, a paged copy): the
/// same points and sidecar.
std::vector<Vec3d> generate_queries(const TriangleSource& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed, const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta);
/// The same from the mesh's summary, for a kind with generate_in_box (the same points and
/// sidecar as from the mesh); std::logic_error for another kind.
std::vector<Vec3d> generate_queries(const MeshSummary& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed, const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta);

}  // namespace bvhbench
