#include "harness/run/run_job.hpp"

#include <stdexcept>

#include "harness/run/system_info.hpp"
#include "harness/util/atomic_file.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"

namespace bvhbench {

using json = nlohmann::json;

std::string dump_result(const json& j) {
  // Strings are made printable where they enter a result; `replace` is the last guard, so that a
  // byte that slipped through costs one U+FFFD, not the result file.
  return j.dump(2, ' ', false, json::error_handler_t::replace);
}

void write_json_atomic(const std::string& path, const json& j) {
  try {
    AtomicOutputFile f(path);
    f.write(dump_result(j) + "\n");
    f.commit();
  } catch (const std::runtime_error& e) {
    // A result path the user gave (run --out, suite --out) that cannot be written is a bad value
    // given by the user: exit code 2, as it always was.
    throw InputError(printable(e.what()));
  }
}

json job_block(const JobSpec& spec) {
  json j;
  const MethodSpec& m = spec.method;
  j["method"] = printable(m.name);
  j["method_spec"] = printable(m.text);
  // The resolved parameters when there are, so that status rows written without running the job
  // (a crash, a query set that could not be made) pair and group like the job's own rows.
  if (m.resolved()) {
    j["params"] = m.params.values();
  } else {
    json given_json = json::object();
    for (const auto& [k, v] : m.given) given_json[printable(k)] = printable(v);
    j["params"] = given_json;
  }
  j["params_key"] = m.params_key();
  j["query"] = to_string(spec.query_type);
  // Paths are the user's bytes (a Linux file name need not be UTF-8); JSON needs UTF-8.
  j["mesh"] = {{"path", printable(spec.mesh_path)}};
  j["queries"] = {{"path", printable(spec.queries_path)}};
  j["repetitions"] = spec.repeat;
  j["threads"] = spec.threads;
  j["truth"] = spec.truth_path.empty() ? json(nullptr) : json(printable(spec.truth_path));
  return j;
}

json make_result(const JobSpec& spec, const std::string& status_code, const std::string& message) {
  json r;
  r["schema"] = "bvhbench.result/1";
  r["context"] = run_context();
  r["job"] = job_block(spec);
  r["status"] = status_code;
  r["message"] = printable(message);
  r["accuracy"] = nullptr;
  return r;
}

json run_job(const JobSpec& spec) { return run_job_group({spec}).front(); }

}  // namespace bvhbench
