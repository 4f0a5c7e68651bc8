#pragma once
/// One job: load the mesh, build one method, replay one query set (measured by the protocol of
/// query_protocol.hpp), and assemble the result JSON of the contract (docs/results.md) and
/// optionally the answers.
#include <string>

#include <nlohmann/json.hpp>

#include "harness/core/method.hpp"
#include "harness/core/method_spec.hpp"

namespace bvhbench {

struct JobSpec {
  std::string mesh_path;
  /// The method, resolved where its text entered (Registry::describe); an unresolved one makes
  /// the job's result rejected_input with the spec's problem.
  MethodSpec method;
  std::string queries_path;  ///< .npy with its .json sidecar
  QueryType query_type = QueryType::inside;
  int repeat = 5;            ///< timed passes after the warm-up
  int threads = 1;
  std::string truth_path;    ///< optional oracle .npz -> accuracy block
  std::string answers_path;  ///< optional .npz of the per-query answers
  double deadline_ns = 1e6;  ///< haptic deadline: 1 kHz loop
  bool progress = true;
};

/// Status codes of the contract: the `status` enum of result_schema.json, the one list of them
/// (ResultSchema::statuses(); a test holds these names to it).
namespace status {
inline constexpr const char* ok = "ok";
inline constexpr const char* unsupported = "unsupported";
inline constexpr const char* rejected_input = "rejected_input";
inline constexpr const char* crash = "crash";
inline constexpr const char* timeout = "timeout";
inline constexpr const char* oom = "oom";
inline constexpr const char* error = "error";
inline constexpr const char* all[] = {ok, unsupported, rejected_input, crash, timeout, oom, error};
}  // namespace status

/// Runs the job in this process. Never throws for a method's or the input's failure: the
/// returned result carries the status and message. (Usage errors in `spec` itself, such as an
/// unknown method, are reported the same way with status rejected_input.)
nlohmann::json run_job(const JobSpec& spec);

/// The `job` block for a spec, as far as it can be filled without running (used for status rows
/// written by the suite when a child dies).
nlohmann::json job_block(const JobSpec& spec);

/// An empty result skeleton with context, job, status and message.
nlohmann::json make_result(const JobSpec& spec, const std::string& status_code,
                           const std::string& message);

/// JSON text of a result, pretty-printed; bytes that are not UTF-8 become U+FFFD instead of an
/// exception (messages and paths are made printable() before they get there).
std::string dump_result(const nlohmann::json& j);

/// Writes JSON to path atomically (AtomicOutputFile), pretty-printed (dump_result). Throws
/// InputError "PATH: cannot write: <why>" when it cannot.
void write_json_atomic(const std::string& path, const nlohmann::json& j);

}  // namespace bvhbench
