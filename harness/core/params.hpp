#pragma once
/// Method parameters: declared by each method (name, type, default, help), chosen on the
/// command line as `NAME:key=value,key=value` (method_spec.hpp), validated before anything is built.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace bvhbench {

enum class ParamType { integer, real, boolean, text, choice };

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::text;
  std::string default_value;         ///< as the user would type it
  std::string help;
  std::vector<std::string> choices;  ///< for ParamType::choice
  double min = -1e308, max = 1e308;  ///< inclusive range for integer/real
};

const char* to_string(ParamType t);

/// A full, validated parameter set: every declared parameter has a value (given or default).
class Params {
 public:
  Params() = default;
  /// Validates `given` against `specs`. Throws InputError naming the method, the key and the
  /// problem for an unknown key, a value of the wrong type, out of range, or not a choice.
  static Params resolve(const std::string& method, const std::vector<ParamSpec>& specs,
                        const std::map<std::string, std::string>& given);

  std::int64_t get_int(const std::string& key) const;
  double get_real(const std::string& key) const;
  bool get_bool(const std::string& key) const;
  const std::string& get(const std::string& key) const;  ///< text or choice (normalised)
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  /// Values that differ from the defaults, "k=v,k=v" sorted by key ("" when all default).
  std::string non_default_string() const;
  const std::map<std::string, std::string>& values() const { return values_; }
  const std::map<std::string, std::string>& given() const { return given_; }

 private:
  std::map<std::string, std::string> values_;  // normalised ("true"/"false", numbers as typed)
  std::map<std::string, std::string> given_;
  std::map<std::string, std::string> defaults_;
};

bool parse_bool(const std::string& s, bool* out);  ///< 1/0, true/false, yes/no, on/off

}  // namespace bvhbench
