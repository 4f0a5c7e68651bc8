#pragma once
/// Answers of one replay pass, the oracle file, and the accuracy block that compares them.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/geometry.hpp"
#include "harness/core/inside_definition.hpp"
#include "harness/core/method.hpp"

namespace bvhbench {

/// What a method answered, query by query, in query order (docs/results.md, "Answers and oracle files").
struct Answers {
  QueryType type = QueryType::inside;
  std::vector<std::uint8_t> inside;      ///< N, inside jobs
  std::vector<double> distance;          ///< N, signed, distance jobs
  std::vector<Vec3d> closest, normal;    ///< N x 3
  std::vector<std::int64_t> triangle;    ///< N, -1 where unknown
  void resize(QueryType t, std::size_t n);
  /// Drops every answer after the first n (the query set's, when other probes' paths follow).
  void keep_first(std::size_t n);
  void write_npz(const std::string& path) const;
};

/// The `accuracy` block (docs/results.md) from a method's answers and an oracle file
/// (`bvhbench truth`). `diagonal` is the mesh's bounding-box diagonal (near-surface threshold and
/// relative errors). `queries_sha256` / `mesh_sha256`, when given, must match the ones the oracle
/// recorded. Throws InputError if the oracle file is malformed or belongs to another query set or
/// mesh. Wrong, NaN or infinite answers never throw: they are what the block measures.
///
/// Inside answers, and the signs of distances, are judged against `inside`, the method's own
/// definition, where the mesh defines it (else, and for an undeclared one, against the oracle's
/// default); the points where the mesh's definitions disagree are counted apart, the first few
/// with their coordinates from `points` (the query set; may be empty), and the mesh is checked
/// against the method's contract.
nlohmann::json compute_accuracy(const Answers& answers, const std::string& truth_path,
                                double diagonal, const std::string& queries_sha256 = "",
                                const std::string& mesh_sha256 = "", const InsideDefinition& inside = {},
                                const std::vector<Vec3d>& points = {});

}  // namespace bvhbench
