// Jobs that share one structure, in one process (run_job.hpp: run_job_group): each job's query
// set read and checked, the mesh loaded and the method built once (or, for a structure read from a
// file, the mesh file's streamed summary and the structure opened), then each job's queries by the
// protocol of query_protocol.hpp, its result assembled as docs/results.md says.
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <new>
#include <numeric>

#include <tbb/global_control.h>

#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/run/accuracy.hpp"
#include "harness/run/calibration.hpp"
#include "harness/run/counted_region.hpp"
#include "harness/run/dataset_manifest.hpp"
#include "harness/run/latency_by_distance.hpp"
#include "harness/run/machine_fingerprint.hpp"
#include "harness/run/query_protocol.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/system_info.hpp"
#include "harness/run/test_slowdown.hpp"
#include "harness/run/thread_replay.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/process_memory.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

namespace {

// ---- the queries block ----------------------------------------------------------------------

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

json latency_block(const QueryMeasurement& m) {
  // One call answered every query: no query has a latency of its own (query_protocol.hpp).
  if (m.batch) return {{"p50", nullptr}, {"p99", nullptr}, {"p999", nullptr}, {"max", nullptr}, {"mean", nullptr}};
  const std::vector<double>& lat = m.latency_ns;  // sorted
  const double mean = m.total ? std::accumulate(lat.begin(), lat.end(), 0.0) / double(m.total) : 0.0;
  return {{"p50", percentile(lat, 0.5)},
          {"p99", percentile(lat, 0.99)},
          {"p999", percentile(lat, 0.999)},
          {"max", lat.empty() ? 0.0 : lat.back()},
          {"mean", mean}};
}

json threads_block(const QueryMeasurement& m, int threads, bool probes) {
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
  return th;
}

/// The result's `queries` block (docs/results.md) from what the protocol measured.
json queries_block(const QueryMeasurement& m, double deadline_ns, int threads, bool probes) {
  json q;
  q["n"] = m.total;
  if (!m.qps.empty()) {
    q["throughput_qps"] = spread(m.qps);
  } else {
    q["throughput_qps"] = {{"median", nullptr}, {"min", nullptr}, {"max", nullptr}, {"samples", json::array()}};
  }
  q["pass_seconds"] = m.pass_seconds;
  q["latency_ns"] = latency_block(m);
  q["deadline_ns"] = deadline_ns;
  const std::vector<double>& lat = m.latency_ns;
  const std::size_t over = std::count_if(lat.begin(), lat.end(), [&](double v) { return v > deadline_ns; });
  q["over_deadline"] = m.batch ? json(nullptr) : json(over);
  q["batch"] = m.batch;
  q["threads"] = threads_block(m, threads, probes);
  return q;
}

// ---- the group ------------------------------------------------------------------------------

/// A failure as a status and a message: the exception being handled, classified.
struct Failure {
  const char* code;
  std::string message;
};

Failure current_failure() {
  try {
    throw;
  } catch (const InputError& e) {
    return {status::rejected_input, e.what()};
  } catch (const UnsupportedError& e) {
    return {status::unsupported, e.what()};
  } catch (const std::bad_alloc&) {
    return {status::oom, "out of memory (std::bad_alloc)"};
  } catch (const std::exception& e) {
    return {status::error, e.what()};
  } catch (...) {
    return {status::error, "unknown exception"};
  }
}

/// One job of the group while it runs: its spec, its result as it fills, what it reads.
struct GroupJob {
  const JobSpec* spec = nullptr;
  json r;
  QuerySet qs;
  bool probes = false;
  std::vector<std::vector<Vec3d>> probe_points;  // probes: every thread's path (path 0 = the set's)
  bool done = false;                             // the result is final
  InsideDefinition inside;  // its configuration's definition of inside (inside_definition.hpp)
};

/// What the jobs share: the method, the mesh's facts, the build's block.
class GroupRun {
 public:
  GroupRun(const std::vector<JobSpec>& specs, std::string build_id, const GroupHooks& hooks)
      : build_id_(std::move(build_id)), hooks_(hooks) {
    for (const JobSpec& s : specs) jobs_.push_back(GroupJob{&s, make_result(s, status::ok, ""), {}, false, {}, false, {}});
  }

  /// The whole group; a failure of a shared step ends every unfinished job with it.
  void run() {
    try {
      create_method();
      for (std::size_t k = 0; k < jobs_.size(); ++k) guarded(k, [&] { read_queries(jobs_[k]); });
      if (runnable() == 0) return;
      if (method_->reads_structure() && !needs_probe_paths()) {
        // A structure read from a file: the mesh's summary from a streamed pass, never the mesh.
        summarize(summarize_mesh_file());
        for (std::size_t k = 0; k < jobs_.size(); ++k) guarded(k, [&] { describe_mesh(jobs_[k]); });
        if (runnable() == 0) return;
        build([&](const BuildContext& ctx) { method_->open(summary_, ctx); });
      } else {
        Mesh mesh = load_mesh();
        summarize(mesh.summary());
        mesh_bytes_ = mesh.bytes();
        for (std::size_t k = 0; k < jobs_.size(); ++k)
          guarded(k, [&] {
            describe_mesh(jobs_[k]);
            make_probe_paths(jobs_[k], mesh);
          });
        if (runnable() == 0) return;
        build([&](const BuildContext& ctx) { method_->build(mesh, ctx); });
        { Mesh released = std::move(mesh); }  // the method keeps what it needs: query memory is its own
        malloc_trim(0);
      }
    } catch (...) {
      const Failure f = current_failure();
      for (std::size_t k = 0; k < jobs_.size(); ++k) fail(k, f.code, f.message);
      return;
    }
    for (std::size_t k = 0; k < jobs_.size(); ++k) guarded(k, [&] { query(k); });
  }

  std::vector<json> results() const {
    std::vector<json> out;
    for (const GroupJob& j : jobs_) out.push_back(j.r);
    return out;
  }

 private:
  const JobSpec& first() const { return *jobs_.front().spec; }

  std::size_t runnable() const {
    return std::size_t(std::count_if(jobs_.begin(), jobs_.end(), [](const GroupJob& j) { return !j.done; }));
  }

  /// Runs a step of job k, unless it is finished; a failure is that job's.
  template <class Step>
  void guarded(std::size_t k, Step step) {
    if (jobs_[k].done) return;
    try {
      step();
    } catch (...) {
      const Failure f = current_failure();
      fail(k, f.code, f.message);
    }
  }

  void finish(std::size_t k) {
    jobs_[k].done = true;
    jobs_[k].qs = QuerySet();  // its points are of no more use
    jobs_[k].probe_points.clear();
    if (hooks_.finished) hooks_.finished(k, jobs_[k].r);
  }

  void fail(std::size_t k, const char* code, const std::string& message) {
    if (jobs_[k].done) return;
    jobs_[k].r["status"] = code;
    jobs_[k].r["message"] = printable(message);  // a library's or a reader's text may not be UTF-8
    finish(k);
  }

  void create_method() {
    const MethodSpec& spec = first().method;
    // Created first: an unresolved spec (an unknown method, a bad option) throws its own message here.
    method_ = apply_test_slowdown(Registry::global().create(spec), spec.name);  // unset: itself
    info_ = spec.info;
    applied_options_ = spec.params.non_default_string();
    // Each job's own configuration: its options differ from the first's in query options at most
    // (build_groups.hpp), which set_query_options gives the method before its queries.
    for (GroupJob& j : jobs_) {
      const Params& params = j.spec->method.params;
      j.inside = resolve_inside(info_->inside, params);
      j.r["job"]["method"] = info_->name;
      j.r["job"]["params"] = params.values();
      j.r["job"]["params_key"] = params.non_default_string();
      j.r["job"]["inside"] = j.inside.to_json();  // what its inside means, judged below (accuracy.hpp)
      j.r["context"] = run_context();  // registration may have noted library versions
    }
  }

  /// The method asks as job k's configuration does (its query options), when another asked last.
  void apply_query_options(const GroupJob& j) {
    const Params& params = j.spec->method.params;
    const std::string key = params.non_default_string();
    if (key == applied_options_) return;
    if (!info_->caps.query_options_after_build)
      throw std::logic_error("jobs of different options grouped for " + info_->name +
                             ", which does not take query options after its build");
    method_->set_query_options(params);
    applied_options_ = key;
  }

  /// The job's query set, and whether the method answers its queries as asked.
  void read_queries(GroupJob& j) {
    const JobSpec& spec = *j.spec;
    j.qs = load_query_set(spec.queries_path);
    j.r["job"]["queries"] = {{"path", printable(j.qs.path)},
                             {"sha256", j.qs.sha256},
                             {"kind", j.qs.kind()},
                             {"n", j.qs.points.size()},
                             {"seed", j.qs.meta.value("seed", json(nullptr))},
                             {"mesh_sha256", j.qs.meta.value("mesh_sha256", json(nullptr))}};
    const std::string with = spec.method.params.non_default_string();
    if (!answers(*info_, *method_, spec.query_type))
      throw UnsupportedError(info_->name + " does not answer " + to_string(spec.query_type) + " queries" +
                             (with.empty() ? std::string() : " with " + with));
    if (spec.threads > 1 && !info_->caps.concurrent_queries)
      throw UnsupportedError(info_->name + " does not declare concurrent queries: threads must be 1 (asked " +
                             std::to_string(spec.threads) + ")");
    j.probes = spec.threads > 1 && replays_as_probes(j.qs);
  }

  Mesh load_mesh() {
    Progress load_progress("loading " + first().mesh_path, 1.0, first().progress);
    Mesh mesh = bvhbench::load_mesh(first().mesh_path, nullptr);
    load_progress.finish();
    return mesh;
  }

  MeshSummary summarize_mesh_file() {
    Progress read_progress("reading " + first().mesh_path, 1.0, first().progress);
    MeshSummary s = bvhbench::summarize_mesh(first().mesh_path, nullptr);
    read_progress.finish();
    return s;
  }

  /// The mesh as every job's result records it.
  void summarize(MeshSummary s) {
    summary_ = std::move(s);
    diagonal_ = summary_.bounds.diagonal();
    mesh_block_ = {{"path", printable(summary_.path)},
                   {"sha256", summary_.sha256},
                   {"triangles", summary_.triangles},
                   {"vertices", summary_.vertices},
                   {"diagonal", diagonal_}};
    // How the mesh was made, where its dataset's manifest says (a stress case, a real model, ...).
    if (json d = dataset_entry(summary_.path, summary_.sha256); !d.is_null()) mesh_block_["dataset"] = d;
  }

  /// Whether some job replays its path as T probes, whose other paths are made on the mesh.
  bool needs_probe_paths() const {
    return std::any_of(jobs_.begin(), jobs_.end(), [](const GroupJob& j) { return !j.done && j.probes; });
  }

  /// The mesh in the job's result.
  void describe_mesh(GroupJob& j) {
    j.r["job"]["mesh"] = mesh_block_;
    if (j.qs.meta.contains("mesh_sha256") && j.qs.meta["mesh_sha256"] != summary_.sha256)
      j.r["job"]["queries"]["mesh_mismatch"] = true;
  }

  /// The threads' queries of a job that replays as probes: T probes of a generated path (made on
  /// the mesh before the build); otherwise the set is split in T parts.
  void make_probe_paths(GroupJob& j, const Mesh& mesh) {
    if (!j.probes) return;
    const int threads = j.spec->threads;
    Progress probe_progress("making " + std::to_string(threads - 1) + " more probe paths", 1.0, j.spec->progress);
    j.probe_points = probe_paths(mesh, j.qs, threads);
    probe_progress.finish();
  }

  /// The build context of the first job that runs: its query type, kind and points' box (every
  /// probe's path too: methods size bands and caches from it).
  BuildContext build_context() const {
    const GroupJob& j = *std::find_if(jobs_.begin(), jobs_.end(), [](const GroupJob& g) { return !g.done; });
    BuildContext ctx;
    ctx.threads = j.spec->threads;
    ctx.query_type = j.spec->query_type;
    ctx.query_bounds = j.qs.bounds();
    for (const auto& path : j.probe_points)
      for (const Vec3d& p : path) ctx.query_bounds.add(p);
    ctx.query_kind = j.qs.kind();
    return ctx;
  }

  /// The method's build (or its structure's opening), timed, with its peak memory.
  template <class Build>
  void build(Build&& build_with) {
    const BuildContext ctx = build_context();
    reset_peak_rss();
    const auto b0 = Clock::now();
    build_with(ctx);
    const auto b1 = Clock::now();
    build_peak_ = peak_rss_bytes();
    structure_bytes_ = method_->structure_bytes();
    build_ = {{"seconds", std::chrono::duration<double>(b1 - b0).count()},
              {"structure_bytes", structure_bytes_},
              {"peak_rss_bytes", build_peak_},
              {"threads", info_->caps.build_threads == BuildThreads::job   ? json(first().threads)
                          : info_->caps.build_threads == BuildThreads::one ? json(1)
                                                                           : json(nullptr)},
              {"jobs", jobs_.size()}};
    if (!build_id_.empty()) build_["id"] = build_id_;
    structure_ = method_->info();
    // A structure read from a file (a store) was built with options of its own: those ran, and
    // those are recorded (the spec's params_key, which names the file, stays the job's key).
    read_options_ = method_->build_options_read();
    // A store records the threads it was built with; the job's own T did not build it.
    if (const auto threads = method_->build_threads_read()) build_["threads"] = *threads;
    if (hooks_.built) hooks_.built(build_);
  }

  /// The shared build in job k's result, as it ran.
  void record_build(std::size_t k) {
    json& r = jobs_[k].r;
    r["build"] = build_;
    r["build"]["position"] = ++queried_;  // 1: the job queried right after the build
    r["structure"] = structure_;
    if (read_options_.empty()) return;
    const Params& params = jobs_[k].spec->method.params;
    r["job"]["params"] = params.with_values(info_->name, info_->params, read_options_).values();
    json keys = json::array();
    for (const auto& kv : read_options_) keys.push_back(kv.first);
    r["job"]["params_read_from_structure"] = keys;
  }

  /// Job k's queries: the counted warm-up pass, the timed passes, the latency pass, its peak
  /// RSS from a mark reset just before (no job is charged another's state), then accuracy.
  void query(std::size_t k) {
    GroupJob& j = jobs_[k];
    const JobSpec& spec = *j.spec;
    if (hooks_.job_starts) hooks_.job_starts(k);
    record_build(k);
    apply_query_options(j);
    const bool peak_reset = reset_peak_rss();
    const std::size_t n = j.qs.points.size();
    // With T > 1 each timed pass is followed by a pass on one thread (the same set, or probe 0's
    // path), so the speed-up compares passes taken together.
    QueryProtocol protocol(*method_, spec.query_type, j.qs.points,
                           j.probes ? probe_streams(j.probe_points) : split_streams(j.qs.points, spec.threads),
                           ThreadStream{j.qs.points.data(), n, 0});
    Answers answers;
    protocol.counted_pass(&answers);
    const QueryMeasurement& m = protocol.measured();
    json counters = json::object();
    for (const Counter& c : m.counters) counters[c.name] = m.total ? double(c.value) / double(m.total) : 0.0;
    j.r["counters"] = counters;
    answers.keep_first(n);  // the oracle and the answers file are for the query set, not the other probes
    // Which of them only compare exactly on a like machine, and the machine they were counted on.
    j.r["machine_dependent"] = {{"counters", info_->machine_dependent_counters},
                                {"fingerprint", machine_fingerprint(method_->machine_facts())}};
    j.r["calibration"] = measure_calibration();
    timed_passes(protocol, spec);
    if (jobs_.size() > 1) end_counted_job(k);  // a lone job's counts stay in callgrind's one file
    j.r["queries"] = queries_block(m, spec.deadline_ns, spec.threads, j.probes);
    j.r["memory"] = {{"structure_bytes", structure_bytes_},
                     {"peak_rss_bytes", std::max(build_peak_, peak_rss_bytes())},
                     {"peak_reset", peak_reset},
                     {"query_rss_bytes", m.query_rss},
                     {"mesh_bytes", mesh_bytes_}};
    if (!spec.answers_path.empty()) answers.write_npz(spec.answers_path);
    if (!spec.truth_path.empty()) {
      j.r["accuracy"] = compute_accuracy(answers, spec.truth_path, diagonal_, j.qs.sha256, summary_.sha256, j.inside,
                                         j.qs.points);
      // Where the method is fast and where slow: the query set's latencies by the oracle's
      // distance to the surface (none in batches: no query has a latency of its own).
      if (!m.batch) {
        const std::vector<double> in_order(m.latency_in_order.begin(), m.latency_in_order.begin() + std::ptrdiff_t(n));
        j.r["queries"]["by_distance"] = latency_by_distance(in_order, spec.truth_path, diagonal_);
      }
    }
    finish(k);
  }

  void timed_passes(QueryProtocol& protocol, const JobSpec& spec) {
    Progress qprog("querying " + info_->name + (spec.threads > 1 ? " on " + std::to_string(spec.threads) + " threads" : ""),
                   spec.repeat * (spec.threads > 1 ? 2 : 1) + 1, spec.progress);
    protocol.timed_passes(spec.repeat, qprog);
    qprog.finish();
  }

  std::string build_id_;
  const GroupHooks& hooks_;
  std::vector<GroupJob> jobs_;
  const MethodInfo* info_ = nullptr;
  std::string applied_options_;  ///< the configuration the method asks as now (params_key)
  std::unique_ptr<Method> method_;
  double diagonal_ = 0;
  MeshSummary summary_;
  std::size_t mesh_bytes_ = 0,  // the harness's copy of the mesh (0: not loaded)
              build_peak_ = 0, structure_bytes_ = 0, queried_ = 0;
  json mesh_block_, build_, structure_;
  std::map<std::string, std::string> read_options_;
};

}  // namespace

std::vector<json> run_job_group(const std::vector<JobSpec>& specs, const std::string& build_id, const GroupHooks& hooks) {
  if (specs.empty()) return {};
  GroupRun group(specs, build_id, hooks);
  // The job's thread budget, for the build and the queries alike.
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::max(1, specs.front().threads));
  group.run();
  return group.results();
}

}  // namespace bvhbench
