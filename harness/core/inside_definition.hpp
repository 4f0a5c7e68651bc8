#pragma once
/// What "inside" means: the definitions a method may compute, the input it promises to handle,
/// and the declaration that says which of them a method (in each configuration) computes.
///
/// "Inside" has more than one definition, and on some meshes they disagree (docs/results.md,
/// "Inside: definitions"):
///   - ray parity: a ray from p crosses the surface an odd number of times. Defined (the same for
///     every ray) when the mesh is closed: every edge used an even number of times.
///   - winding number: w(p) > 1/2, w the integer winding number of a closed, consistently
///     oriented mesh. Orientation counts: an inside-out mesh has nothing inside.
///   - nonzero winding: w(p) != 0 (the union of the shells, whatever their orientation).
///   - generalized winding number: w(p) > threshold, w the sum of the triangles' signed solid
///     angles / 4 pi (Jacobson et al. 2013). Defined on any triangle soup; on a closed,
///     consistently oriented mesh it is the winding number.
/// They agree on a closed, outward-oriented mesh whose shells do not overlap; where they do not
/// (overlapping shells, |w| > 1, an inverted or a flipped part) a point is *definition-dependent*.
/// A method is judged against its own definition (run/accuracy.hpp), and a method run on input
/// outside its contract is shown as such, apart from one that fails inside it.
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

class Params;

enum class InsideRule {
  undeclared,                  ///< the method says nothing: judged against the oracle's default, as before
  ray_parity,
  winding_number,              ///< w > 1/2
  nonzero_winding,             ///< w != 0
  generalized_winding_number,  ///< w > threshold
};

/// The input a method promises to handle; each one includes the ones after it.
enum class InputContract {
  undeclared,                ///< nothing promised and nothing checked
  any,                       ///< any triangle soup: open, broken, inconsistently oriented
  closed,                    ///< every edge used an even number of times (self-intersections allowed)
  closed_oriented,           ///< and consistently oriented: each edge used as often in each direction
  closed_oriented_manifold,  ///< and every edge shared by exactly two triangles
  /// and no self-intersection, outward: w(p) is 0 or 1 everywhere (what a sign from the closest
  /// feature, a pseudonormal, needs). Checked as far as the oracle can: at the query points.
  embedded,
};

const char* to_string(InsideRule r);
const char* to_string(InputContract c);
/// The names to_string prints; InputError naming `what` and the choices otherwise.
InsideRule parse_inside_rule(const std::string& s, const std::string& what);
InputContract parse_input_contract(const std::string& s, const std::string& what);

/// A method's inside, resolved for one configuration: what its inside(p), and the sign of its
/// distance(p), compute.
struct InsideDefinition {
  InsideRule rule = InsideRule::undeclared;
  /// Computes an approximation of the rule (a sampled field, a fast winding number): its wrong
  /// answers are its error, measured, not a failure.
  bool approximate = false;
  double threshold = 0.5;  ///< generalized_winding_number only: inside iff w > threshold
  InputContract contract = InputContract::undeclared;

  bool declared() const { return rule != InsideRule::undeclared; }
  /// {"definition", "approximate", "threshold" (null unless generalized), "contract"}: what a
  /// result records as job.inside and `bvhbench methods --json` lists.
  nlohmann::json to_json() const;
  /// "ray parity; input: closed", "generalized winding number > 0.5 (approximate); input: any".
  std::string text() const;
};

/// One line of a method's declaration: the definition of the configurations whose options have
/// the values in `when` (option name -> canonical value; empty: every configuration).
struct InsideVariant {
  std::map<std::string, std::string> when;
  InsideDefinition definition;
  /// A real option whose value is the threshold (brute force's winding_threshold), "" for none.
  std::string threshold_option;
};

/// The definition of the configuration `params` under `declaration`: the first variant whose
/// `when` it matches (an undeclared definition when none does, or the declaration is empty).
InsideDefinition resolve_inside(const std::vector<InsideVariant>& declaration, const Params& params);

/// The declaration as `bvhbench methods --json` lists it: [{"when": {...}, ...definition}].
nlohmann::json declaration_json(const std::vector<InsideVariant>& declaration);

}  // namespace bvhbench
