#pragma once
/// Typed parameters, the one declaration of both a method's options and a query kind's
/// generator parameters: declared once (name, type, role, default, help, range or choices), given
/// as text (a method as `NAME:key=value,key=value`, method_spec.hpp; a query kind's as
/// `bvhbench queries --param k=v` or a suite's `params:`), checked and turned into typed values
/// before anything is built or generated. Everything else reads that one declaration: the
/// canonical key results group by (printed from the typed values, so 5 and 5.0 are one key),
/// `bvhbench methods` and `bvhbench kinds`, the values a method's constructor or a generator
/// gets, a suite's sweeps and its check of a query set's parameters.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace bvhbench {

enum class ParamType { integer, real, boolean, text, choice };

/// Whether an option shapes the structure (another value means another build) or only how the
/// queries are asked of it. A structure read from a file (a store) carries its own build options.
/// A query kind's parameters shape the query set: they are declared `query`.
enum class ParamRole { build, query };

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::text;
  ParamRole role = ParamRole::build;
  std::string default_value;         ///< as the user would type it
  std::string help;
  std::vector<std::string> choices;  ///< for ParamType::choice
  double min = -1e308, max = 1e308;  ///< inclusive range for integer/real
  bool min_excluded = false;         ///< the range is (min, max]: e.g. a speed, a length > 0
};

const char* to_string(ParamType t);
const char* to_string(ParamRole r);

/// One option's value, typed as its declaration says.
struct ParamValue {
  ParamType type = ParamType::text;
  std::int64_t integer = 0;
  double real = 0;
  bool boolean = false;
  std::string text;  ///< text or choice
  /// The canonical text: integers in decimal, reals in the shortest form that reads back to the
  /// same double (5.0 -> "5", 0.50 -> "0.5"), booleans "true"/"false", text and choices as given.
  std::string canonical() const;
  bool operator==(const ParamValue& o) const { return canonical() == o.canonical(); }
};

/// A full, validated option set: every declared option has a typed value (given or default).
class Params {
 public:
  Params() = default;
  /// Validates `given` against `specs`. Throws InputError naming the owner, the key and the
  /// problem for an unknown key (with the nearest declared one), a value of the wrong type, out
  /// of range, or not a choice. `owner` begins the messages: "method NAME", "query kind 'K'".
  static Params resolve_for(const std::string& owner, const std::vector<ParamSpec>& specs,
                            const std::map<std::string, std::string>& given);
  /// resolve_for("method " + method, ...): a method's options.
  static Params resolve(const std::string& method, const std::vector<ParamSpec>& specs,
                        const std::map<std::string, std::string>& given) {
    return resolve_for("method " + method, specs, given);
  }

  /// These options with `read` (option -> text, e.g. a store's own build options) put in place
  /// of the values they name, checked against the same declaration. The defaults stay, so
  /// non_default_string() still tells what differs from them.
  Params with_values(const std::string& method, const std::vector<ParamSpec>& specs,
                     const std::map<std::string, std::string>& read) const;

  /// Typed reads; a key not declared, or declared with another type, is a programming error
  /// (std::logic_error), never a user's.
  std::int64_t get_int(const std::string& key) const;
  double get_real(const std::string& key) const;
  bool get_bool(const std::string& key) const;
  const std::string& get(const std::string& key) const;  ///< text or choice
  const ParamValue& value(const std::string& key) const;
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  /// Whether the user gave `key` (even at its default value).
  bool given(const std::string& key) const { return given_.count(key) != 0; }
  /// Values that differ from the defaults, "k=v,k=v" sorted by key, canonical ("" when all default).
  std::string non_default_string() const;
  /// The same, of the options named in `only`.
  std::string non_default_string(const std::set<std::string>& only) const;
  /// Every option's canonical text, by key (what results record as job.params).
  std::map<std::string, std::string> values() const;
  /// The options the user gave, as typed (not canonical).
  const std::map<std::string, std::string>& given() const { return given_; }

 private:
  /// non_default_string() of the options `keep(name)` accepts.
  template <class Keep>
  std::string non_default_where(Keep keep) const;

  std::map<std::string, ParamValue> values_;
  std::map<std::string, std::string> given_;
  std::map<std::string, ParamValue> defaults_;
};

bool parse_bool(const std::string& s, bool* out);  ///< 1/0, true/false, yes/no, on/off

}  // namespace bvhbench
