#include "harness/run/child_outcome_json.hpp"

namespace bvhbench {

using json = nlohmann::json;

json child_outcome_to_json(const ChildOutcome& o) {
  return {{"exited", o.exited},       {"exit_code", o.exit_code}, {"signal", o.signal},
          {"timed_out", o.timed_out}, {"seconds", o.seconds},     {"stderr_tail", o.stderr_tail}};
}

namespace {

template <class T>
T member_or(const json& j, const char* key, T fallback) {
  if (!j.is_object() || !j.contains(key)) return fallback;
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    return fallback;
  }
}

}  // namespace

ChildOutcome child_outcome_from_json(const json& j) {
  ChildOutcome o;
  o.exited = member_or(j, "exited", o.exited);
  o.exit_code = member_or(j, "exit_code", o.exit_code);
  o.signal = member_or(j, "signal", o.signal);
  o.timed_out = member_or(j, "timed_out", o.timed_out);
  o.seconds = member_or(j, "seconds", o.seconds);
  o.stderr_tail = member_or(j, "stderr_tail", o.stderr_tail);
  return o;
}

}  // namespace bvhbench
