#include "harness/run/suite_estimate.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "build_info.hpp"
#include "harness/core/query_set.hpp"
#include "harness/run/calibration.hpp"
#include "harness/run/job_executor.hpp"
#include "harness/util/json_path.hpp"
#include "harness/util/progress.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

// What the estimate assumes where no result says better. Measured on this project's 2-core
// machine (suites/README.md, "Expected time"): loading a binary PLY and hashing it, per triangle;
// a child's fixed cost (start, registration, calibration kernel, accuracy); the oracle (exact
// winding numbers over a hierarchy), per triangle to build and per query x log2 triangles.
constexpr double kLoadSecondsPerTriangle = 1.5e-7;
constexpr double kChildSeconds = 0.6;
constexpr double kOracleSecondsPerTriangle = 6e-7;
constexpr double kOracleSecondsPerQueryLog = 2e-6;
constexpr double kQueryGenSecondsPerPoint = 2e-6;
// A probe path's (haptic, contact) triangle grid, per triangle, beyond the load: two passes over
// the triangles in memory, more when the mesh is paged (the 128M model: 43 s loaded, 53 s paged).
constexpr double kProbeGridSecondsPerTriangle = 2.5e-7;
// Where no method has run at all: a build per triangle x log2 triangles, a query.
constexpr double kBuildSecondsPerTriangleLog = 4e-8;
constexpr double kQuerySeconds = 2e-5;

double log2_of(double t) { return std::log2(std::max(t, 2.0)); }

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size();
  return m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]);
}

double number_or(const json& j, std::initializer_list<const char*> path, double fallback) {
  const json& v = json_at(j, path);
  return v.is_number() ? v.get<double>() : fallback;
}

std::string text_or(const json& j, std::initializer_list<const char*> path) {
  const json& v = json_at(j, path);
  return v.is_string() ? v.get<std::string>() : std::string();
}

// ---- triangle counts ---------------------------------------------------------------------------

double ply_faces(std::ifstream& f) {
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("element face ", 0) == 0) return std::atof(line.c_str() + 13);
    if (line.rfind("end_header", 0) == 0) break;
  }
  return 0;
}

double off_faces(std::ifstream& f) {
  std::string line;
  std::getline(f, line);  // OFF
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream counts(line);
    double v = 0, faces = 0;
    counts >> v >> faces;
    return faces;
  }
  return 0;
}

/// OBJ face lines (a polygon of k corners is k - 2 triangles); a file too big to read for an
/// estimate is priced by its size.
double obj_faces(const std::string& path) {
  std::error_code ec;
  const auto bytes = fs::file_size(path, ec);
  if (ec) return 0;
  if (bytes > (64u << 20)) return double(bytes) / 40.0;
  std::ifstream f(path);
  std::string line;
  double t = 0;
  while (std::getline(f, line)) {
    if (line.size() < 2 || line[0] != 'f' || line[1] != ' ') continue;
    std::istringstream corners(line.substr(2));
    std::string c;
    int k = 0;
    while (corners >> c) ++k;
    t += std::max(1, k - 2);
  }
  return t;
}

double stl_faces(const std::string& path) {
  std::error_code ec;
  const auto bytes = fs::file_size(path, ec);
  std::ifstream f(path, std::ios::binary);
  char header[84] = {};
  if (ec || !f.read(header, 84)) return 0;
  std::uint32_t n = 0;
  std::memcpy(&n, header + 80, 4);
  if (84 + 50ull * n == bytes) return n;
  return double(bytes) / 250.0;  // ASCII: about 250 bytes a facet
}

double file_triangles(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  std::ifstream f(path, std::ios::binary);
  if (!f) return 0;
  if (ext == ".ply") return ply_faces(f);
  if (ext == ".off") return off_faces(f);
  if (ext == ".stl") return stl_faces(path);
  if (ext == ".obj") return obj_faces(path);
  return 0;
}

json read_json_file(const fs::path& path) {
  std::ifstream f(path);
  if (!f) return nullptr;
  try {
    return json::parse(f);
  } catch (const json::exception&) {
    return nullptr;
  }
}

/// The manifest beside the mesh (datasets-scripts/make_datasets.py), which lists it.
double manifest_triangles(const fs::path& mesh) {
  const json m = read_json_file(mesh.parent_path() / "manifest.json");
  if (!m.is_object() || !m.contains("meshes") || !m["meshes"].is_array()) return 0;
  for (const json& e : m["meshes"])
    if (e.is_object() && e.value("file", "") == mesh.filename().string()) return number_or(e, {"triangles"}, 0);
  return 0;
}

/// The preset's declared size: data/PRESET/NAME.ply in datasets-scripts/preset_sizes.json.
double declared_triangles(const fs::path& mesh) {
  static const json sizes =
      read_json_file(fs::path(BVHBENCH_SOURCE_DIR) / "datasets-scripts" / "preset_sizes.json");
  const std::string preset = mesh.parent_path().filename().string(), name = mesh.stem().string();
  return number_or(sizes, {"presets", preset.c_str(), name.c_str()}, 0);
}

}  // namespace

double mesh_triangles(const std::string& path) {
  const fs::path p(path);
  std::error_code ec;
  if (fs::exists(p, ec))
    if (const double t = file_triangles(path); t > 0) return t;
  if (const double t = manifest_triangles(p); t > 0) return t;
  return declared_triangles(p);
}

// ---- observations ------------------------------------------------------------------------------

bool observe(const json& r, CostObservation* o) {
  if (!r.is_object() || r.value("status", "") != "ok" || !r.contains("elapsed_seconds")) return false;
  const double elapsed = number_or(r, {"elapsed_seconds"}, -1);
  const double qps = number_or(r, {"queries", "throughput_qps", "median"}, 0);
  const double n = number_or(r, {"queries", "n"}, 0);
  if (elapsed < 0 || qps <= 0 || n <= 0) return false;
  o->method = text_or(r, {"job", "method"});
  o->params_key = text_or(r, {"job", "params_key"});
  o->query = text_or(r, {"job", "query"});
  o->kind = text_or(r, {"job", "queries", "kind"});
  o->batch = json_at(r, {"queries", "batch"}) == json(true);
  o->triangles = std::max(1.0, number_or(r, {"job", "mesh", "triangles"}, 1));
  o->n = n;
  const double threads = std::max(1.0, number_or(r, {"job", "threads"}, 1));
  const double passes = number_or(r, {"job", "repetitions"}, 1) + 2;  // counted warm-up, timed, latency
  o->query_seconds = threads / qps;
  // A later job of a group did not load the mesh nor build (its elapsed time starts after the
  // previous job's result): its build is an observation all the same, but not of its time.
  o->loaded_mesh = number_or(r, {"build", "position"}, 1) <= 1;
  o->build_seconds = number_or(r, {"build", "seconds"}, 0);
  o->rest_seconds = std::max(0.0, elapsed - (o->loaded_mesh ? o->build_seconds : 0.0) - passes * n / qps);
  const bool same_kernel = text_or(r, {"calibration", "kernel"}) == kCalibrationKernel;
  o->kernel_seconds = same_kernel ? number_or(r, {"calibration", "median_seconds"}, 0) : 0;
  return true;
}

std::vector<std::string> SuiteEstimator::default_folders(const std::string& out) {
  std::vector<std::string> folders = {out};
  const fs::path root(BVHBENCH_SOURCE_DIR);
  std::error_code ec;
  std::set<std::string> seen = {fs::weakly_canonical(out, ec).string()};
  std::vector<std::string> results;
  for (const auto& e : fs::directory_iterator(root / "results", ec))
    if (e.is_directory()) results.push_back(e.path().string());
  std::sort(results.begin(), results.end());
  results.push_back((root / "tests" / "fixtures" / "results_small").string());
  for (const std::string& r : results)
    if (seen.insert(fs::weakly_canonical(r, ec).string()).second) folders.push_back(r);
  return folders;
}

SuiteEstimator::SuiteEstimator(const std::vector<std::string>& folders, double kernel_seconds_here) {
  std::error_code ec;
  for (const std::string& folder : folders) {
    const fs::path runs = fs::is_directory(fs::path(folder) / "runs", ec) ? fs::path(folder) / "runs" : fs::path(folder);
    for (const auto& e : fs::directory_iterator(runs, ec)) {
      if (e.path().extension() != ".json") continue;
      json r;
      CostObservation o;
      if (read_result_file(e.path().string(), &r) && observe(r, &o)) obs_.push_back(o);
    }
  }
  fit_rest();  // the rest (a child's start, loading) is mostly not the processor's: not scaled
  scale_to_machine(kernel_seconds_here);
  std::vector<double> builds, queries;
  for (const CostObservation& o : obs_) {
    builds.push_back(o.build_seconds / (o.triangles * log2_of(o.triangles)));
    queries.push_back(o.query_seconds);
  }
  median_build_per_triangle_ = builds.empty() ? kBuildSecondsPerTriangleLog : median_of(builds);
  median_query_ = queries.empty() ? kQuerySeconds : median_of(queries);
}

/// Each observation's build and query costs times (kernel here / kernel then), held within
/// [1/20, 20]: the calibration kernel is a query loop's pointer chase and arithmetic, so it moves
/// as the builds and queries do when the machine, or its load, changes.
void SuiteEstimator::scale_to_machine(double kernel_seconds_here) {
  if (kernel_seconds_here <= 0) return;
  for (CostObservation& o : obs_) {
    if (o.kernel_seconds <= 0) continue;
    const double f = std::clamp(kernel_seconds_here / o.kernel_seconds, 0.05, 20.0);
    o.build_seconds *= f;
    o.query_seconds *= f;
    rescaled_ += std::abs(f - 1) > 0.1 ? 1 : 0;
  }
}

/// rest = fixed + per triangle x T, least squares over the jobs that loaded their mesh; the
/// per-triangle part defaults to kLoadSecondsPerTriangle where the sizes do not tell it.
void SuiteEstimator::fit_rest() {
  std::vector<const CostObservation*> loaded;
  for (const CostObservation& o : obs_)
    if (o.loaded_mesh) loaded.push_back(&o);
  double st = 0, sr = 0, stt = 0, str = 0;
  for (const CostObservation* o : loaded) {
    st += o->triangles, sr += o->rest_seconds, stt += o->triangles * o->triangles, str += o->triangles * o->rest_seconds;
  }
  const double m = double(loaded.size()), den = m * stt - st * st;
  double slope = m >= 2 && den > 0 ? (m * str - st * sr) / den : 0;
  // Small meshes alone say nothing of loading millions of triangles: keep the measured default
  // unless the observations span a million triangles.
  double t_max = 0;
  for (const CostObservation* o : loaded) t_max = std::max(t_max, o->triangles);
  if (slope <= 0 || t_max < 1e6) slope = kLoadSecondsPerTriangle;
  rest_per_triangle_ = slope;
  std::vector<double> fixed;
  for (const CostObservation* o : loaded) fixed.push_back(std::max(0.0, o->rest_seconds - slope * o->triangles));
  rest_fixed_ = fixed.empty() ? kChildSeconds : median_of(fixed);
}

namespace {

/// The observation nearest `job`: the same method (and query type, when `query`), then what
/// `score` prefers; null when the method never ran.
template <class Score>
const CostObservation* nearest(const std::vector<CostObservation>& obs, const JobPlan& job, bool query, Score score) {
  const CostObservation* best = nullptr;
  for (const CostObservation& o : obs) {
    if (o.method != job.method.name) continue;
    if (query && o.query != to_string(job.query)) continue;
    if (!best || score(o) < score(*best)) best = &o;
  }
  return best;
}

/// The names of the options in a params key ("k=v,k=v" -> "k,k"): two configurations that set the
/// same options (a store, a cache) price alike where no result of the very same one exists.
std::string option_names(const std::string& params_key) {
  std::string names;
  std::size_t at = 0;
  while (at < params_key.size()) {
    const std::size_t comma = std::min(params_key.find(',', at), params_key.size());
    const std::string pair = params_key.substr(at, comma - at);
    names += (names.empty() ? "" : ",") + pair.substr(0, pair.find('='));
    at = comma + 1;
  }
  return names;
}

bool batch_job(const JobPlan& job) {
  return job.method.resolved() && job.method.params.has("batch") && job.method.params.get_bool("batch");
}

}  // namespace

double SuiteEstimator::build_seconds(const JobPlan& job, double t, bool* known) const {
  const std::string key = job.method.params_key();
  const std::string names = option_names(key);
  const CostObservation* o = nearest(obs_, job, false, [&](const CostObservation& c) {
    return std::make_tuple(c.params_key != key, option_names(c.params_key) != names, std::abs(std::log(t / c.triangles)));
  });
  *known = o != nullptr;
  if (!o) return median_build_per_triangle_ * t * log2_of(t);
  // A hierarchy's build grows as T log T.
  return o->build_seconds * (t / o->triangles) * (log2_of(t) / log2_of(o->triangles));
}

double SuiteEstimator::query_seconds(const JobPlan& job, double t, bool* known) const {
  const std::string key = job.method.params_key();
  const bool batch = batch_job(job);
  const CostObservation* o = nearest(obs_, job, true, [&](const CostObservation& c) {
    const double apart = std::abs(std::log(t / c.triangles));
    return std::make_tuple(c.batch != batch, apart > std::log(2.0), c.params_key != key,
                           option_names(c.params_key) != option_names(key), c.kind != job.queries.kind, apart);
  });
  *known = o != nullptr;
  if (!o) return median_query_;
  // A query's cost grows with the depth of a hierarchy: about log T.
  return o->query_seconds * (1.0 + std::max(0.0, std::log2(t / o->triangles)) / 4.0);
}

SuitePrice SuiteEstimator::price(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs,
                                 const std::vector<std::vector<bool>>& to_run, const std::vector<BuildGroup>& groups,
                                 bool shared_builds, const std::string& data_dir) const {
  SuitePrice p;
  p.observations = obs_.size();
  p.rescaled = rescaled_;
  p.rounds = int(to_run.size());
  p.job_seconds.assign(jobs.size(), 0.0);
  p.build_seconds.assign(jobs.size(), 0.0);
  p.job_runs.assign(jobs.size(), 0);
  std::map<std::string, double> tris;
  auto triangles = [&](const JobPlan& j) {
    auto it = tris.find(j.mesh.path);
    if (it == tris.end()) {
      it = tris.emplace(j.mesh.path, mesh_triangles(j.mesh.path)).first;
      if (it->second <= 0) ++p.unknown_meshes;
    }
    return std::max(1.0, it->second);
  };
  std::vector<bool> guessed(jobs.size(), false);
  for (const std::vector<bool>& round : to_run)
    price_round(cfg, jobs, round, groups, shared_builds, triangles, p, guessed);
  std::vector<bool> any_round(jobs.size(), false);  // the query sets and oracles are made once
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    any_round[i] = p.job_runs[i] > 0;
    p.jobs += any_round[i] ? 1 : 0;
    p.guessed += guessed[i] ? 1 : 0;
  }
  p.data_seconds = data_seconds(cfg, jobs, any_round, data_dir, triangles);
  return p;
}

void SuiteEstimator::price_round(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs,
                                 const std::vector<bool>& to_run, const std::vector<BuildGroup>& groups,
                                 bool shared_builds, const std::function<double(const JobPlan&)>& triangles,
                                 SuitePrice& p, std::vector<bool>& guessed) const {
  for (const BuildGroup& g : groups) {
    bool first = true;  // the job that loads the mesh and builds
    for (std::size_t i : g.jobs) {
      if (!to_run[i]) continue;
      const JobPlan& j = jobs[i];
      const double t = triangles(j);
      ++p.runs;
      ++p.job_runs[i];
      if (!j.method.resolved()) continue;  // recorded at once, never run
      bool build_known = true, query_known = true;
      const bool builds = first || !shared_builds;
      double s = rest_fixed_ + double(cfg.repeat + 2) * double(j.queries.n) * query_seconds(j, t, &query_known);
      if (builds) {
        const double build = build_seconds(j, t, &build_known);
        p.build_seconds[i] += build;
        s += rest_per_triangle_ * t + build;
      }
      p.builds += builds ? 1 : 0;
      guessed[i] = guessed[i] || !(build_known && query_known);
      p.job_seconds[i] += s;
      first = false;
    }
  }
}

/// The query sets (and oracles) of the jobs to run that the cache does not hold yet.
double SuiteEstimator::data_seconds(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs,
                                    const std::vector<bool>& to_run, const std::string& data_dir,
                                    const std::function<double(const JobPlan&)>& triangles) const {
  std::set<std::string> made;
  double s = 0;
  std::error_code ec;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const JobPlan& j = jobs[i];
    if (!to_run[i] || !j.method.resolved() || !j.queries.file.empty()) continue;
    const std::string label = j.queries.label();
    if (!made.insert(j.mesh.path + "|" + label).second) continue;
    if (fs::exists(fs::path(data_dir) / "queries" / (file_safe(j.mesh.name) + "__" + label + ".npy"), ec)) continue;
    const double t = triangles(j), n = double(j.queries.n);
    s += rest_fixed_ + rest_per_triangle_ * t + kQueryGenSecondsPerPoint * n;
    const QueryKind* kind = find_query_kind(j.queries.kind);
    if (kind && kind->ordered) s += kProbeGridSecondsPerTriangle * t;
    if (cfg.truth)
      s += rest_fixed_ + rest_per_triangle_ * t + kOracleSecondsPerTriangle * t + kOracleSecondsPerQueryLog * n * log2_of(t);
  }
  return s;
}

double SuitePrice::total() const {
  double s = data_seconds;
  for (double j : job_seconds) s += j;
  return s;
}

double SuitePrice::run_seconds(std::size_t job) const {
  if (job >= job_seconds.size() || job >= job_runs.size() || job_runs[job] <= 0) return 0.0;
  return job_seconds[job] / job_runs[job];
}

std::string SuitePrice::describe() const {
  double jobs_s = 0;
  for (double j : job_seconds) jobs_s += j;
  std::ostringstream o;
  o << jobs << " job(s) to run";
  if (rounds > 1) o << " in " << rounds << " rounds (" << runs << " run(s))";
  o << ", " << builds << " build(s): expected ~" << format_seconds(total()) << " (jobs "
    << format_seconds(jobs_s) << ", query sets and oracles " << format_seconds(data_seconds) << "; priced from "
    << observations << " result(s) on disk";
  if (rescaled) o << ", " << rescaled << " of them scaled to this machine's speed by the calibration kernel";
  if (guessed) o << ", " << guessed << " job(s) of methods never run here priced at the median rates";
  if (unknown_meshes) o << ", " << unknown_meshes << " mesh(es) of unknown size";
  o << ")";
  return o.str();
}

json price_json(const SuitePrice& price, const std::vector<JobPlan>& jobs) {
  json listed = json::array();
  for (std::size_t i = 0; i < jobs.size() && i < price.job_seconds.size(); ++i) {
    if (price.job_seconds[i] <= 0) continue;
    listed.push_back({{"id", jobs[i].id},
                      {"triangles", mesh_triangles(jobs[i].mesh.path)},
                      {"seconds", price.job_seconds[i]},
                      {"build_seconds", price.build_seconds[i]},
                      {"runs", i < price.job_runs.size() ? price.job_runs[i] : 0}});
  }
  return {{"seconds", price.total()},
          {"data_seconds", price.data_seconds},
          {"jobs", price.jobs},
          {"rounds", price.rounds},
          {"runs", price.runs},
          {"builds", price.builds},
          {"observations", price.observations},
          {"priced", listed}};
}

double time_left(double expected_left, double expected_done, double actual_done) {
  if (expected_done <= 0 || actual_done <= 0) return expected_left;
  return expected_left * std::clamp(actual_done / expected_done, 0.05, 20.0);
}

}  // namespace bvhbench
