#pragma once
/// `key=value` text, as a method spec (`NAME:k=v,k=v`), `bvhbench queries --param k=v` and a
/// method's own commands take it: the one parser of such pairs.
#include <map>
#include <string>
#include <utility>

#include "harness/util/errors.hpp"

namespace bvhbench {

/// Splits "k=v" at its first '=' (the value may hold more). Throws InputError
/// "WHERE: 'PAIR' is not key=value" for a pair without '=' or without a key.
inline std::pair<std::string, std::string> split_key_value(const std::string& pair, const std::string& where) {
  const auto eq = pair.find('=');
  if (eq == std::string::npos || eq == 0) throw InputError(where + ": '" + pair + "' is not key=value");
  return {pair.substr(0, eq), pair.substr(eq + 1)};
}

/// Adds the pair "k=v" to `out`. Throws InputError "WHERE: ..." as split_key_value does, and for
/// a key given twice.
inline void add_key_value(const std::string& pair, const std::string& where, std::map<std::string, std::string>& out) {
  auto [key, value] = split_key_value(pair, where);
  if (out.count(key)) throw InputError(where + ": '" + key + "' given twice");
  out.emplace(std::move(key), std::move(value));
}

}  // namespace bvhbench
