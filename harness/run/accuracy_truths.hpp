#pragma once
/// What an oracle file (`bvhbench truth`) says about inside under each definition
/// (core/inside_definition.hpp), and what it says about the mesh that a method's contract is
/// checked against. Oracle files written before the definitions were recorded are read too: on a
/// closed mesh the parity follows from the integer winding number, on an open one only the
/// generalized winding number is defined.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "harness/core/inside_definition.hpp"
#include "harness/io/npy.hpp"

namespace bvhbench {

/// Array `key` of oracle file `path` (opened as `t`), checked: its dtype and n * cols values.
/// Throws InputError naming the file, the array and the problem.
const NpyArray& oracle_array(const std::map<std::string, NpyArray>& t, const std::string& path,
                             const std::string& key, const std::string& dtype, std::size_t n, std::size_t cols);

/// String array `key` of an oracle file (its first element), "" when absent or not a string.
std::string oracle_string(const std::map<std::string, NpyArray>& t, const std::string& key);

class InsideTruths {
 public:
  /// Reads the arrays of oracle file `path` (already opened as `t`, which must outlive this) for
  /// n queries. Throws InputError naming the file when an array is missing or has another length.
  InsideTruths(const std::map<std::string, NpyArray>& t, const std::string& path, std::size_t n);

  /// The oracle's default definition ("exact" on closed meshes, "winding_number" on open ones):
  /// the one a method that declares none is judged against, as before declarations.
  const std::string& default_definition() const { return default_definition_; }
  /// The definitions defined on this mesh, by name.
  const std::vector<std::string>& defined() const { return defined_; }
  bool is_defined(InsideRule r) const;

  /// What `d` says at query i: its own rule where defined on this mesh, else the oracle's default.
  bool inside(const InsideDefinition& d, std::size_t i) const;
  /// The name of what `d` is judged against here: its rule, or "oracle_default".
  std::string judged_against(const InsideDefinition& d) const;
  /// Whether the definitions defined on this mesh (each at threshold 1/2) disagree at query i.
  bool dependent(std::size_t i) const;
  /// Each defined definition's answer at query i, by name.
  std::map<std::string, bool> says(std::size_t i) const;
  double winding(std::size_t i) const { return winding_ ? winding_[i] : 0.0; }
  /// Ambiguous under the generalized winding number: an open mesh's |w| within 1/4 of 1/2.
  bool ambiguous(std::size_t i) const;

  /// Why this mesh is outside contract `c` ("3 boundary edges: not closed and consistently
  /// oriented"), "" when it is inside it or `c` is undeclared. `embedded` is checked at the
  /// query points (a winding number other than 0 or 1 is a witness against it).
  std::string contract_problem(InputContract c) const;

 private:
  bool rule_says(InsideRule r, double threshold, std::size_t i) const;

  std::string default_definition_;
  std::vector<std::string> defined_;
  std::vector<InsideRule> rules_;  ///< defined_, parsed
  const std::uint8_t* default_inside_ = nullptr;
  const double* winding_ = nullptr;
  std::vector<std::uint8_t> parity_;
  std::int64_t boundary_edges_ = 0;
  std::optional<std::int64_t> odd_edges_, nonmanifold_edges_;
  std::size_t n_ = 0;
};

}  // namespace bvhbench
