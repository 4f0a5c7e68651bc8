#pragma once
/// Query sets (ARCHITECTURE.md, "Query sets"): NAME.npy (float64, N x 3) plus NAME.json with at
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
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "geometry.hpp"

namespace bvhbench {

struct Mesh;

struct QuerySet {
  std::string path;         ///< the .npy, .xyz or .csv
  std::string sha256;       ///< of the file's bytes
  nlohmann::json meta;      ///< the sidecar; without one {kind: file, n, format, ordered: true}
  std::vector<Vec3d> points;
  std::string kind() const { return meta.value("kind", std::string("unknown")); }
  Box3d bounds() const;
};

/// "Q.npy" -> "Q.json"; likewise for Q.xyz and Q.csv.
std::string sidecar_path(const std::string& points_path);
/// The points of a query file, N x 3 in the file's order: .npy (read_points_npy), .xyz or .csv
/// (read_points_text), told apart by the extension (any case). Throws InputError naming the file
/// and the problem (another extension, a malformed file, NaN/inf).
std::vector<Vec3d> read_query_points(const std::string& path);
/// Reads a query file and its sidecar, if there is one; throws InputError naming the file and the
/// problem (a malformed points file, a sidecar with bad JSON, without kind/n/seed, or with an n
/// that does not match).
QuerySet load_query_set(const std::string& points_path);
/// Parses and checks the sidecar JSON `text` of the query set `points_path`, which holds
/// `n_points` points; `side` names the sidecar in messages. Returns the sidecar (a JSON object
/// with a string kind, n = n_points and a seed). Throws InputError naming `side` and the problem.
nlohmann::json parse_sidecar(std::string_view text, const std::string& side, const std::string& points_path,
                             std::size_t n_points);
/// Writes Q.npy and Q.json atomically; meta gets n and (if missing) created_by.
void write_query_set(const std::string& npy_path, const std::vector<Vec3d>& points,
                     nlohmann::json meta);

/// Deterministic random source: splitmix64-seeded xoshiro256**, identical on every platform
/// (std::uniform_real_distribution is not), with the few distributions generators need.
class Rng {
 public:
  explicit Rng(std::uint64_t seed);
  std::uint64_t next();
  double uniform();                     ///< [0, 1) with 53 random bits
  double uniform(double lo, double hi);
  double normal();                      ///< standard normal (Box-Muller, deterministic)
  std::uint64_t below(std::uint64_t n);  ///< uniform integer in [0, n)
 private:
  std::uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0;
};

/// A kind of query set. Registered in query_kinds.cpp (one line each).
struct QueryKind {
  std::string name;
  std::string description;
  /// Parameters with defaults (all recorded in the sidecar); user values override by key.
  std::map<std::string, double> defaults;
  /// Generates n points on `mesh` from `seed` with the resolved parameters.
  std::function<std::vector<Vec3d>(const Mesh& mesh, std::size_t n, std::uint64_t seed,
                                   const std::map<std::string, double>& params)>
      generate;
  bool ordered = false;  ///< a path whose order matters (haptic)
};

const std::vector<QueryKind>& query_kinds();
const QueryKind* find_query_kind(const std::string& name);

/// Generates a query set and its sidecar meta (kind, n, seed, mesh_sha256, mesh path, params,
/// ordered). Throws InputError for an unknown kind or parameter.
std::vector<Vec3d> generate_queries(const Mesh& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed,
                                    const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta);

}  // namespace bvhbench
