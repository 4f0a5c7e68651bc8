#pragma once
/// One job: load the mesh, build one method, replay one query set (measured by the protocol of
/// query_protocol.hpp), and assemble the result JSON of the contract (docs/results.md) and
/// optionally the answers. Several jobs of one structure: run_job_group, one build for all
/// (run_job_group.cpp); a job alone is a group of one.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

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
/// A job of a group (jobs sharing one structure in one child) that never ran: the child died in
/// an earlier job of the group (its status says how). `suite --resume` runs it again.
inline constexpr const char* not_run = "not_run";
inline constexpr const char* all[] = {ok, unsupported, rejected_input, crash, timeout, oom, error, not_run};
}  // namespace status

/// Runs the job in this process: a group of one (run_job_group). Never throws for a method's or
/// the input's failure: the returned result carries the status and message. (Usage errors in
/// `spec` itself, such as an unknown method, are reported the same way with status
/// rejected_input.)
nlohmann::json run_job(const JobSpec& spec);

/// What a group's caller hears while it runs (run_job_group), each hook optional.
struct GroupHooks {
  /// The shared structure is built: its `build` block (build.id, seconds, bytes, ...).
  std::function<void(const nlohmann::json& build)> built;
  /// Job `k` (an index into the group's specs) starts its queries.
  std::function<void(std::size_t k)> job_starts;
  /// Job `k`'s result is final (called once per job, in the order they end).
  std::function<void(std::size_t k, const nlohmann::json& result)> finished;
};

/// Runs jobs that share one structure, in this process: the same mesh, method spec and threads
/// (and repeat, deadline); their query sets, query types, oracles and answers files may differ.
/// Each job's query set is read and checked first (a job that cannot run is finished at once:
/// rejected_input, unsupported); then the mesh is loaded and the method built once (a structure
/// read from a file, Method::reads_structure: opened from the mesh file's streamed summary, the
/// mesh never loaded, unless T probes need their paths made on it), with the build context of
/// the first job that runs (a method whose build reads the queries is never
/// grouped past what it declares: registry.hpp, StructureSharing); then each job's queries in
/// turn, the protocol of query_protocol.hpp, the peak-RSS mark reset before each. Every result
/// records the shared build: build.seconds and structure_bytes are the one build's, build.id is
/// `build_id` (when not ""), build.jobs the group's size and build.position the job's place.
/// A failure of a shared step (the mesh, the build) is every unfinished job's status; one of a
/// job's own queries is that job's. Throws as run_job does not: never.
std::vector<nlohmann::json> run_job_group(const std::vector<JobSpec>& specs, const std::string& build_id = "",
                                          const GroupHooks& hooks = {});

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
