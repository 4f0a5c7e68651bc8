#include "harness/run/run_job.hpp"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <new>
#include <numeric>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/run/accuracy.hpp"
#include "harness/run/calibration.hpp"
#include "harness/run/dataset_manifest.hpp"
#include "harness/run/latency_by_distance.hpp"
#include "harness/run/machine_fingerprint.hpp"
#include "harness/run/query_protocol.hpp"
#include "harness/run/system_info.hpp"
#include "harness/run/test_slowdown.hpp"
#include "harness/run/thread_replay.hpp"
#include "harness/util/atomic_file.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/process_memory.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

using Clock = std::chrono::steady_clock;
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

namespace {

double percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  double pos = q * (sorted.size() - 1);
  std::size_t i = std::size_t(pos);
  double f = pos - i;
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] * (1 - f) + sorted[i + 1] * f;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return percentile(v, 0.5);
}

json spread(const std::vector<double>& v) {
  return {{"median", median(v)},
          {"min", *std::min_element(v.begin(), v.end())},
          {"max", *std::max_element(v.begin(), v.end())},
          {"samples", v}};
}

/// The result's `queries` block (docs/results.md) from what the protocol measured.
json queries_block(const QueryMeasurement& m, double deadline_ns, int threads, bool probes) {
  const std::vector<double>& lat = m.latency_ns;  // sorted
  json q;
  q["n"] = m.total;
  if (!m.qps.empty()) {
    q["throughput_qps"] = spread(m.qps);
  } else {
    q["throughput_qps"] = {{"median", nullptr}, {"min", nullptr}, {"max", nullptr}, {"samples", json::array()}};
  }
  q["pass_seconds"] = m.pass_seconds;
  if (m.batch) {
    // One call answered every query: no query has a latency of its own (query_protocol.hpp).
    q["latency_ns"] = {{"p50", nullptr}, {"p99", nullptr}, {"p999", nullptr}, {"max", nullptr}, {"mean", nullptr}};
  } else {
    const double mean = m.total ? std::accumulate(lat.begin(), lat.end(), 0.0) / double(m.total) : 0.0;
    q["latency_ns"] = {{"p50", percentile(lat, 0.5)},
                       {"p99", percentile(lat, 0.99)},
                       {"p999", percentile(lat, 0.999)},
                       {"max", lat.empty() ? 0.0 : lat.back()},
                       {"mean", mean}};
  }
  q["deadline_ns"] = deadline_ns;
  const std::size_t over = std::count_if(lat.begin(), lat.end(), [&](double v) { return v > deadline_ns; });
  q["over_deadline"] = m.batch ? json(nullptr) : json(over);
  q["batch"] = m.batch;
  json th;
  th["count"] = threads;
  th["mode"] = probes ? "probes" : "split";
  const bool with_single = threads > 1;
  if (with_single && !m.single_qps.empty()) {
    const double single_median = median(m.single_qps);
    th["single_thread_qps"] = spread(m.single_qps);
    th["speedup"] = single_median > 0 && !m.qps.empty() ? json(median(m.qps) / single_median) : json(nullptr);
  } else {
    th["single_thread_qps"] = nullptr;
    th["speedup"] = with_single ? json(nullptr) : json(1.0);
  }
  q["threads"] = th;
  return q;
}

}  // namespace

json run_job(const JobSpec& spec) {
  json r = make_result(spec, status::ok, "");
  auto fail = [&](const char* code, const std::string& msg) {
    r["status"] = code;
    r["message"] = printable(msg);  // a library's or a reader's text may not be UTF-8
  };
  try {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                std::max(1, spec.threads));
    const MethodInfo* info = spec.method.info;
    auto method = apply_test_slowdown(Registry::global().create(spec.method), info->name);  // unset: itself
    const Params& params = spec.method.params;
    r["job"]["method"] = info->name;
    r["job"]["params"] = params.values();
    r["job"]["params_key"] = params.non_default_string();
    r["context"] = run_context();  // registration may have noted library versions

    QuerySet qs = load_query_set(spec.queries_path);
    r["job"]["queries"] = {{"path", printable(qs.path)},
                           {"sha256", qs.sha256},
                           {"kind", qs.kind()},
                           {"n", qs.points.size()},
                           {"seed", qs.meta.value("seed", json(nullptr))},
                           {"mesh_sha256", qs.meta.value("mesh_sha256", json(nullptr))}};

    if (!answers(*info, *method, spec.query_type)) {
      fail(status::unsupported, info->name + " does not answer " + to_string(spec.query_type) +
                                    " queries" +
                                    (params.non_default_string().empty()
                                         ? std::string()
                                         : " with " + params.non_default_string()));
      return r;
    }

    if (spec.threads > 1 && !info->caps.concurrent_queries) {
      fail(status::unsupported, info->name + " does not declare concurrent queries: threads must be 1 (asked " +
                                    std::to_string(spec.threads) + ")");
      return r;
    }

    Progress load_progress("loading " + spec.mesh_path, 1.0, spec.progress);
    Mesh mesh = load_mesh(spec.mesh_path, nullptr);
    load_progress.finish();
    const Box3d bounds = mesh.bounds();
    const double diagonal = bounds.diagonal();
    const std::string mesh_sha256 = mesh.sha256;  // the mesh itself is released after build
    r["job"]["mesh"] = {{"path", printable(mesh.path)},
                        {"sha256", mesh.sha256},
                        {"triangles", mesh.num_triangles()},
                        {"vertices", mesh.vertices.size()},
                        {"diagonal", diagonal}};
    // How the mesh was made, where its dataset's manifest says (a stress case, a real model, ...).
    if (json d = dataset_entry(mesh.path, mesh.sha256); !d.is_null()) r["job"]["mesh"]["dataset"] = d;
    if (qs.meta.contains("mesh_sha256") && qs.meta["mesh_sha256"] != mesh.sha256)
      r["job"]["queries"]["mesh_mismatch"] = true;

    // ---- the threads' queries: T probes of a generated path, or the set split in T parts ------
    const bool probes = spec.threads > 1 && replays_as_probes(qs);
    std::vector<std::vector<Vec3d>> probe_points;  // probes: every thread's path (path 0 = the set's)
    if (probes) {
      Progress probe_progress("making " + std::to_string(spec.threads - 1) + " more probe paths", 1.0, spec.progress);
      probe_points = probe_paths(mesh, qs, spec.threads);
      probe_progress.finish();
    }

    // ---- build ------------------------------------------------------------------------------
    BuildContext ctx;
    ctx.threads = spec.threads;
    ctx.query_type = spec.query_type;
    ctx.query_bounds = qs.bounds();
    for (const auto& path : probe_points)  // every probe's path: methods size bands and caches from it
      for (const Vec3d& p : path) ctx.query_bounds.add(p);
    ctx.query_kind = qs.kind();
    const std::size_t mesh_bytes = mesh.bytes();
    reset_peak_rss();
    auto b0 = Clock::now();
    method->build(mesh, ctx);
    auto b1 = Clock::now();
    const std::size_t build_peak = peak_rss_bytes();
    const std::size_t structure_bytes = method->structure_bytes();
    r["build"] = {{"seconds", std::chrono::duration<double>(b1 - b0).count()},
                  {"structure_bytes", structure_bytes},
                  {"peak_rss_bytes", build_peak},
                  {"threads", info->caps.build_threads == BuildThreads::job   ? json(spec.threads)
                              : info->caps.build_threads == BuildThreads::one ? json(1)
                                                                              : json(nullptr)}};
    r["structure"] = method->info();
    // A structure read from a file (a store) was built with options of its own: those ran, and
    // those are recorded (the spec's params_key, which names the file, stays the job's key).
    if (const auto read = method->build_options_read(); !read.empty()) {
      r["job"]["params"] = params.with_values(info->name, info->params, read).values();
      json keys = json::array();
      for (const auto& kv : read) keys.push_back(kv.first);
      r["job"]["params_read_from_structure"] = keys;
    }

    // The method keeps what it needs: release the mesh so query memory is the method's own.
    { Mesh released = std::move(mesh); }
    malloc_trim(0);
    reset_peak_rss();

    // ---- the protocol: counted warm-up pass, timed passes, latency pass (query_protocol.hpp) ----
    const auto& pts = qs.points;
    const std::size_t n = pts.size();
    // With T > 1 each timed pass is followed by a pass on one thread (the same set, or probe 0's
    // path), so the speed-up compares passes taken together.
    QueryProtocol protocol(*method, spec.query_type,
                           pts, probes ? probe_streams(probe_points) : split_streams(pts, spec.threads),
                           ThreadStream{pts.data(), n, 0});
    Answers answers;
    protocol.counted_pass(&answers);
    const QueryMeasurement& m = protocol.measured();
    json counters = json::object();
    for (const Counter& c : m.counters) counters[c.name] = m.total ? double(c.value) / double(m.total) : 0.0;
    r["counters"] = counters;
    // The oracle and the answers file are for the query set: the other probes' paths have none.
    answers.keep_first(n);
    // Which of them only compare exactly on a like machine, and the machine they were counted on.
    r["machine_dependent"] = {{"counters", info->machine_dependent_counters},
                              {"fingerprint", machine_fingerprint(method->machine_facts())}};

    r["calibration"] = measure_calibration();
    Progress qprog("querying " + info->name + (spec.threads > 1 ? " on " + std::to_string(spec.threads) + " threads" : ""),
                   spec.repeat * (spec.threads > 1 ? 2 : 1) + 1, spec.progress);
    protocol.timed_passes(spec.repeat, qprog);
    qprog.finish();
    r["queries"] = queries_block(m, spec.deadline_ns, spec.threads, probes);
    const std::size_t query_rss = m.query_rss;

    const std::size_t query_peak = peak_rss_bytes();
    r["memory"] = {{"structure_bytes", structure_bytes},
                   {"peak_rss_bytes", std::max(build_peak, query_peak)},
                   {"query_rss_bytes", query_rss},
                   {"mesh_bytes", mesh_bytes}};

    // ---- answers and accuracy -----------------------------------------------------------------
    if (!spec.answers_path.empty()) answers.write_npz(spec.answers_path);
    if (!spec.truth_path.empty()) {
      r["accuracy"] = compute_accuracy(answers, spec.truth_path, diagonal, qs.sha256, mesh_sha256);
      // Where the method is fast and where slow: the query set's latencies by the oracle's
      // distance to the surface (none in batches: no query has a latency of its own).
      if (!m.batch) {
        const std::vector<double> in_order(m.latency_in_order.begin(), m.latency_in_order.begin() + std::ptrdiff_t(n));
        r["queries"]["by_distance"] = latency_by_distance(in_order, spec.truth_path, diagonal);
      }
    }
  } catch (const InputError& e) {
    fail(status::rejected_input, e.what());
  } catch (const UnsupportedError& e) {
    fail(status::unsupported, e.what());
  } catch (const std::bad_alloc&) {
    fail(status::oom, "out of memory (std::bad_alloc)");
  } catch (const std::exception& e) {
    fail(status::error, e.what());
  } catch (...) {
    fail(status::error, "unknown exception");
  }
  return r;
}

}  // namespace bvhbench
