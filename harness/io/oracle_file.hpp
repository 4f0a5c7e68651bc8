#pragma once
/// The oracle file (`bvhbench truth --out T.npz`; docs/results.md, "Oracle"): the exact answers of
/// core/oracle.hpp for one query set, with the hashes of the mesh and the query set they belong to.
#include <string>

#include "harness/core/oracle.hpp"

namespace bvhbench {

/// Writes the oracle file (docs/results.md, "Oracle") atomically.
void write_oracle_npz(const std::string& path, const OracleAnswers& a, const std::string& mesh_sha256,
                      const std::string& queries_sha256);

}  // namespace bvhbench
