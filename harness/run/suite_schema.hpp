#pragma once
/// The grammar of a suite file (suites/README.md, "Format"), declared once: the keys each level
/// of the YAML may hold. suite.cpp checks every map it reads against it before it reads a value,
/// so that a misspelt or misplaced key (`repet:`, `threds:`, `parms:`, a query kind's parameter
/// beside `kind` instead of under `params:`) is refused with the file, the line and the key
/// probably meant, instead of running another experiment than the one asked for.
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "harness/core/params.hpp"

namespace bvhbench {

/// The maps of a suite file whose keys are fixed. A query kind's and a method's `params:` are
/// checked against their own declarations (query_set.hpp, the method's ParamSpecs).
enum class SuiteLevel {
  top,          ///< name, repeat, rounds, timeout_s, memory_limit_mb, truth, matrices
  matrix,       ///< meshes, queries, query, methods, threads
  mesh,         ///< {path:, name:}
  query_set,    ///< {kind:, n:, seed:, params:}
  points_file,  ///< {file:, name:}
  method,       ///< {name:, params:}
  all_methods,  ///< {all: true, except: [...]}
};

/// The keys `level` holds, in the order suites/README.md gives them.
const std::vector<std::string>& suite_keys(SuiteLevel level);

/// Refuses the first key of the map `node` that `level` does not hold (keys starting with '_',
/// a place for YAML anchors, are left alone): InputError naming `file`, the key's line, and what
/// was probably meant: a key of this level one or two letters away, where the key belongs when
/// it is another level's, or `params: {KEY: ...}` when it is one of `params_beside` (the query
/// kind's or the method's parameters, given beside `kind:` or `name:`).
void check_suite_keys(const std::string& file, const YAML::Node& node, SuiteLevel level,
                      const std::vector<ParamSpec>& params_beside = {});

/// InputError "FILE: WHAT (line N)" at `node`'s line (when yaml-cpp knows it).
[[noreturn]] void suite_error(const std::string& file, const YAML::Node& node, const std::string& what);

}  // namespace bvhbench
