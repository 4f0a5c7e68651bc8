#pragma once
/// Query sets on disk (docs/architecture.md, "Contracts": query sets): NAME.npy (float64, N x 3) plus NAME.json, the
/// sidecar, with at least kind, n, seed, mesh_sha256 and the generator's parameters; or points made
/// elsewhere without a sidecar (kind `file`, see core/query_set.hpp).
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/geometry.hpp"
#include "harness/core/query_set.hpp"

namespace bvhbench {

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

}  // namespace bvhbench
