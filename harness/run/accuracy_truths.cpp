#include "harness/run/accuracy_truths.hpp"

#include <cmath>

#include "harness/util/errors.hpp"

namespace bvhbench {

const NpyArray& oracle_array(const std::map<std::string, NpyArray>& t, const std::string& path,
                             const std::string& key, const std::string& dtype, std::size_t n, std::size_t cols) {
  auto it = t.find(key);
  if (it == t.end()) throw file_error(path, "oracle has no '" + key + "' array (is it a bvhbench truth file?)");
  const NpyArray& a = it->second;
  if (a.dtype != dtype) throw file_error(path, "oracle '" + key + "' has dtype " + a.dtype + ", expected " + dtype);
  std::size_t want = n * cols;
  if (a.size() != want)
    throw file_error(path, "oracle '" + key + "' has " + std::to_string(a.size()) + " values, expected " +
                               std::to_string(want) + " (does it belong to this query set?)");
  return a;
}

std::string oracle_string(const std::map<std::string, NpyArray>& t, const std::string& key) {
  auto d = t.find(key);
  return d == t.end() ? std::string() : d->second.unicode_value(0);
}

namespace {

std::optional<std::int64_t> count_of(const std::map<std::string, NpyArray>& t, const std::string& path,
                                     const std::string& key) {
  if (!t.count(key)) return std::nullopt;
  return *oracle_array(t, path, key, "<i8", 1, 1).as<std::int64_t>();
}

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < s.size()) {
    std::size_t end = s.find(',', at);
    if (end == std::string::npos) end = s.size();
    if (end > at) out.push_back(s.substr(at, end - at));
    at = end + 1;
  }
  return out;
}

}  // namespace

InsideTruths::InsideTruths(const std::map<std::string, NpyArray>& t, const std::string& path, std::size_t n)
    : n_(n) {
  default_definition_ = oracle_string(t, "definition");
  default_inside_ = oracle_array(t, path, "inside", "|b1", n, 1).as<std::uint8_t>();
  if (t.count("winding")) winding_ = oracle_array(t, path, "winding", "<f8", n, 1).as<double>();
  // Zero-area triangles left out where the oracle counted so (solid_boundary_edges).
  boundary_edges_ = count_of(t, path, "solid_boundary_edges").value_or(count_of(t, path, "boundary_edges").value_or(0));
  odd_edges_ = count_of(t, path, "odd_edges");
  nonmanifold_edges_ = count_of(t, path, "nonmanifold_edges");
  if (t.count("definitions")) {
    defined_ = split_commas(oracle_string(t, "definitions"));
  } else if (winding_) {  // an oracle file from before: what its winding number implies
    if (default_definition_ == "exact") defined_ = {"ray_parity", "winding_number", "nonzero_winding"};
    defined_.push_back("generalized_winding_number");
  }
  if (!winding_) defined_.clear();  // nothing to judge a definition with but the default
  for (const std::string& d : defined_) rules_.push_back(parse_inside_rule(d, path + ": oracle 'definitions'"));
  if (t.count("parity")) {
    const std::uint8_t* p = oracle_array(t, path, "parity", "|b1", n, 1).as<std::uint8_t>();
    parity_.assign(p, p + n);
  } else if (is_defined(InsideRule::ray_parity)) {  // closed: the parity of the integer winding number
    parity_.resize(n);
    for (std::size_t i = 0; i < n; ++i) parity_[i] = std::fmod(std::abs(std::round(winding_[i])), 2.0) == 1.0;
  }
}

bool InsideTruths::is_defined(InsideRule r) const {
  for (InsideRule d : rules_)
    if (d == r) return true;
  return false;
}

bool InsideTruths::rule_says(InsideRule r, double threshold, std::size_t i) const {
  switch (r) {
    case InsideRule::ray_parity: return parity_[i] != 0;
    case InsideRule::winding_number: return winding_[i] > 0.5;
    // w is an integer where this is defined, but for a rounding residue of the strips of
    // zero-area triangles' edges: |w| > 1/2 is w != 0 without it.
    case InsideRule::nonzero_winding: return std::abs(winding_[i]) > 0.5;
    case InsideRule::generalized_winding_number: return winding_[i] > threshold;
    default: return default_inside_[i] != 0;
  }
}

bool InsideTruths::inside(const InsideDefinition& d, std::size_t i) const {
  return is_defined(d.rule) ? rule_says(d.rule, d.threshold, i) : default_inside_[i] != 0;
}

std::string InsideTruths::judged_against(const InsideDefinition& d) const {
  return is_defined(d.rule) ? to_string(d.rule) : "oracle_default";
}

bool InsideTruths::dependent(std::size_t i) const {
  bool first = true, seen = false;
  for (InsideRule r : rules_) {
    const bool s = rule_says(r, 0.5, i);
    if (!first && s != seen) return true;
    seen = s;
    first = false;
  }
  return false;
}

std::map<std::string, bool> InsideTruths::says(std::size_t i) const {
  std::map<std::string, bool> out;
  for (InsideRule r : rules_) out[to_string(r)] = rule_says(r, 0.5, i);
  return out;
}

bool InsideTruths::ambiguous(std::size_t i) const {
  return default_definition_ == "winding_number" && winding_ && std::abs(std::abs(winding_[i]) - 0.5) < 0.25;
}

std::string InsideTruths::contract_problem(InputContract c) const {
  if (c == InputContract::undeclared || c == InputContract::any) return "";
  const std::string edges = " edge(s) used an odd number of times: not closed";
  if (odd_edges_ && *odd_edges_ > 0) return std::to_string(*odd_edges_) + edges;
  if (!odd_edges_ && boundary_edges_ > 0)  // an oracle file from before the counts
    return std::to_string(boundary_edges_) + " boundary edge(s): not closed";
  if (c == InputContract::closed) return "";
  if (boundary_edges_ > 0)
    return std::to_string(boundary_edges_) + " boundary edge(s) counted with their orientation: not consistently oriented";
  if (c == InputContract::closed_oriented) return "";
  if (nonmanifold_edges_ && *nonmanifold_edges_ > 0)
    return std::to_string(*nonmanifold_edges_) + " edge(s) shared by more than two triangles: not manifold";
  if (c == InputContract::closed_oriented_manifold || !winding_) return "";
  // Embedded and outward: w is 0 or 1 wherever it is; a query point elsewhere is a witness.
  std::size_t witnesses = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    const double w = std::round(winding_[i]);
    witnesses += w != 0.0 && w != 1.0;
  }
  if (witnesses)
    return std::to_string(witnesses) + " query point(s) with a winding number other than 0 or 1: "
           "self-intersecting or inside out";
  return "";
}

}  // namespace bvhbench
