#pragma once
/// A method as a suite or the command line names it, "NAME" or "NAME:key=value,key=value",
/// parsed once where the text enters the harness (`run --method`, a suite's `methods:` entry)
/// and passed on as a MethodSpec from there: to the suite's job plans, the job, the registry
/// that creates the method. Text crosses one boundary only: the suite gives each child process
/// `run --method TEXT`, and the child parses it once.
#include <map>
#include <string>

#include "harness/core/params.hpp"

namespace bvhbench {

struct MethodInfo;

struct MethodSpec {
  /// As given, byte for byte: what results record as job.method_spec, what job ids are made
  /// of, what a child process gets as --method.
  std::string text;
  /// NAME; the whole text when it could not be parsed.
  std::string name;
  /// The key=value pairs as typed (not yet checked against the method's parameters).
  std::map<std::string, std::string> given;
  /// The registered method (Registry::describe / resolve); null when the spec is not resolved.
  const MethodInfo* info = nullptr;
  /// Every declared parameter, given or default, validated and normalised; set with `info`.
  Params params;
  /// Why the spec could not be parsed or resolved: the InputError message, "" when resolved.
  std::string problem;

  bool resolved() const { return info != nullptr; }
  /// The parameters off their defaults, "k=v,k=v" sorted by key, normalised: the canonical key
  /// that results group by (job.params_key). "" when all are default or the spec is unresolved.
  std::string params_key() const { return resolved() ? params.non_default_string() : std::string(); }
};

/// Splits `text` into NAME and its key/value pairs (MethodSpec::text, name, given; not resolved).
/// Throws InputError "method spec 'TEXT': ..." for an empty name, a pair without '=' or without
/// a key, or a key given twice. A pair's value is any text without ','; empty pairs are skipped.
MethodSpec parse_method_spec(const std::string& text);

}  // namespace bvhbench
