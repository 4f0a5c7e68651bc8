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

#include "harness/core/batch_answers.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/run/accuracy.hpp"
#include "harness/run/calibration.hpp"
#include "harness/run/machine_fingerprint.hpp"
#include "harness/run/system_info.hpp"
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

double percentile(std::vector<double>& sorted, double q) {
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

/// Reused output buffers of a batch method's calls, so that a timed pass allocates nothing.
struct BatchBuffers {
  std::vector<std::uint8_t> inside;
  std::vector<DistanceResult> distance;
};

/// One call answering every point, checked for the count of answers it gave.
void batch_call(BatchAnswers& m, QueryType qt, const std::vector<Vec3d>& pts, BatchBuffers& out) {
  if (qt == QueryType::inside) {
    out.inside.assign(pts.size(), 0);
    m.inside_batch(pts, out.inside);
    if (out.inside.size() != pts.size())
      throw std::runtime_error("inside_batch gave " + std::to_string(out.inside.size()) +
                               " answers for " + std::to_string(pts.size()) + " points");
  } else {
    out.distance.assign(pts.size(), DistanceResult{});
    m.distance_batch(pts, out.distance);
    if (out.distance.size() != pts.size())
      throw std::runtime_error("distance_batch gave " + std::to_string(out.distance.size()) +
                               " answers for " + std::to_string(pts.size()) + " points");
  }
}

/// One timed pass of a batch method (one call answering every point, path reset first, untimed):
/// its wall time in seconds. The answers land in `batch`, so the call cannot be optimised away.
double timed_batch_pass(Method& method, BatchAnswers& m, QueryType qt, const std::vector<Vec3d>& pts,
                        BatchBuffers& batch) {
  method.reset_path();
  auto t0 = Clock::now();
  batch_call(m, qt, pts, batch);
  auto t1 = Clock::now();
  return std::chrono::duration<double>(t1 - t0).count();
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
    auto method = Registry::global().create(spec.method);
    const MethodInfo* info = spec.method.info;
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
                  {"peak_rss_bytes", build_peak}};
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

    // ---- counted warm-up pass: answers and work counters ----------------------------------------
    const auto& pts = qs.points;
    const std::size_t n = pts.size();
    ThreadedReplay replay(*method, spec.query_type,
                          probes ? probe_streams(probe_points) : split_streams(pts, spec.threads));
    const std::size_t total = replay.total();  // queries per pass, over all threads
    Answers answers;
    // A batch method (a Python method's batch=true) answers the whole set in one call; it declares
    // no concurrent queries, so it runs on one thread (threads > 1 was refused above).
    BatchAnswers* const batcher = batch_answers(*method);
    const bool batch = batcher != nullptr;
    BatchBuffers batch_buffers;
    if (batch) {
      answers.resize(spec.query_type, n);
      method->reset_counters();
      method->reset_path();
      batch_call(*batcher, spec.query_type, pts, batch_buffers);
      if (spec.query_type == QueryType::inside) {
        answers.inside = batch_buffers.inside;
      } else {
        for (std::size_t i = 0; i < n; ++i) {
          const DistanceResult& d = batch_buffers.distance[i];
          answers.distance[i] = d.distance;
          answers.closest[i] = d.closest;
          answers.normal[i] = d.normal;
          answers.triangle[i] = d.triangle;
        }
      }
    } else {
      replay.counted_pass(&answers);
    }
    json counters = json::object();
    for (const Counter& c : replay.counters())
      counters[c.name] = total ? double(c.value) / double(total) : 0.0;
    r["counters"] = counters;
    // The oracle and the answers file are for the query set: the other probes' paths have none.
    answers.keep_first(n);
    // Which of them only compare exactly on a like machine, and the machine they were counted on.
    r["machine_dependent"] = {{"counters", info->machine_dependent_counters},
                              {"fingerprint", machine_fingerprint(method->machine_facts())}};
    std::size_t query_rss = current_rss_bytes();

    r["calibration"] = measure_calibration();
    // ---- throughput: `repeat` passes on T threads; with T > 1 each followed by a pass on one
    // thread (the same set, or probe 0's path), so the speed-up compares passes taken together --
    const bool with_single = spec.threads > 1;
    const ThreadStream single_stream{pts.data(), n, 0};
    std::vector<double> qps, pass_seconds, single_qps;
    Progress qprog("querying " + info->name + (spec.threads > 1 ? " on " + std::to_string(spec.threads) + " threads" : ""),
                   spec.repeat * (with_single ? 2 : 1) + 1, spec.progress);
    for (int rep = 0; rep < spec.repeat; ++rep) {
      double s = batch ? timed_batch_pass(*method, *batcher, spec.query_type, pts, batch_buffers) : replay.timed_pass();
      pass_seconds.push_back(s);
      qps.push_back(s > 0 ? double(total) / s : 0.0);
      query_rss = std::max(query_rss, current_rss_bytes());
      if (with_single) {
        const double s1 = replay.single_thread_pass(single_stream);
        single_qps.push_back(s1 > 0 ? double(n) / s1 : 0.0);
        qprog.update(2 * rep + 2);
      } else {
        qprog.update(rep + 1);
      }
    }

    // ---- latency: one pass with per-query timestamps, on every thread ---------------------------
    // A batch method answers every query in one call: no query has a latency of its own, so none
    // is recorded (the fields are null) rather than the pass time spread evenly over the queries.
    std::vector<double> lat;
    if (!batch) replay.latency_pass(&lat);
    qprog.finish();
    query_rss = std::max(query_rss, current_rss_bytes());
    std::size_t over = std::count_if(lat.begin(), lat.end(), [&](double v) { return v > spec.deadline_ns; });
    double mean = total ? std::accumulate(lat.begin(), lat.end(), 0.0) / double(total) : 0.0;
    std::sort(lat.begin(), lat.end());
    json q;
    q["n"] = total;
    if (!qps.empty()) {
      q["throughput_qps"] = {{"median", median(qps)},
                             {"min", *std::min_element(qps.begin(), qps.end())},
                             {"max", *std::max_element(qps.begin(), qps.end())},
                             {"samples", qps}};
    } else {
      q["throughput_qps"] = {{"median", nullptr}, {"min", nullptr}, {"max", nullptr}, {"samples", json::array()}};
    }
    q["pass_seconds"] = pass_seconds;
    if (batch) {
      q["latency_ns"] = {{"p50", nullptr}, {"p99", nullptr}, {"p999", nullptr}, {"max", nullptr}, {"mean", nullptr}};
    } else {
      q["latency_ns"] = {{"p50", percentile(lat, 0.5)},
                         {"p99", percentile(lat, 0.99)},
                         {"p999", percentile(lat, 0.999)},
                         {"max", lat.empty() ? 0.0 : lat.back()},
                         {"mean", mean}};
    }
    q["deadline_ns"] = spec.deadline_ns;
    q["over_deadline"] = batch ? json(nullptr) : json(over);
    q["batch"] = batch;
    json th;
    th["count"] = spec.threads;
    th["mode"] = probes ? "probes" : "split";
    if (with_single && !single_qps.empty()) {
      const double single_median = median(single_qps);
      th["single_thread_qps"] = {{"median", single_median},
                                 {"min", *std::min_element(single_qps.begin(), single_qps.end())},
                                 {"max", *std::max_element(single_qps.begin(), single_qps.end())},
                                 {"samples", single_qps}};
      th["speedup"] = single_median > 0 && !qps.empty() ? json(median(qps) / single_median) : json(nullptr);
    } else {
      th["single_thread_qps"] = nullptr;
      th["speedup"] = with_single ? json(nullptr) : json(1.0);
    }
    q["threads"] = th;
    r["queries"] = q;

    const std::size_t query_peak = peak_rss_bytes();
    r["memory"] = {{"structure_bytes", structure_bytes},
                   {"peak_rss_bytes", std::max(build_peak, query_peak)},
                   {"query_rss_bytes", query_rss},
                   {"mesh_bytes", mesh_bytes}};

    // ---- answers and accuracy -----------------------------------------------------------------
    if (!spec.answers_path.empty()) answers.write_npz(spec.answers_path);
    if (!spec.truth_path.empty()) r["accuracy"] = compute_accuracy(answers, spec.truth_path, diagonal, qs.sha256, mesh_sha256);
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
