#include "harness/run/result_set.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <fstream>

#include "harness/core/params.hpp"
#include "harness/run/result_schema.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_input.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

json read_result_file(const std::string& file) {
  std::ifstream f(file, std::ios::binary);
  if (!f) throw file_error(file, "cannot read");
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw file_error(file, "read failed");
  return parse_result(text, file);
}

/// Results written before option values were printed from their typed values kept a real as it
/// was typed ("1.0", "2.50"); they read as they are written now ("1", "2.5"), so that old and new
/// results of one configuration pair (compare's key holds job.params). Integers, booleans and
/// texts were already written canonical; a text that reads whole as a number with a point or an
/// exponent is taken for a real.
///
/// A `threads` option of cgal_aabb ("recorded only"), embree (its device's threads) and openvdb
/// (a cap on the job's) was removed: a build runs on the job's build threads (build.threads). At
/// its default it said nothing a result does not, so it is dropped from older results.
void migrate_params(json& r) {
  auto job = r.find("job");
  if (job == r.end() || !job->is_object()) return;
  auto params = job->find("params");
  if (params == job->end() || !params->is_object()) return;
  static const std::map<std::string, std::string> removed_threads = {
      {"cgal_aabb", "1"}, {"embree", "1"}, {"openvdb", "0"}};
  const auto method = job->find("method");
  if (method != job->end() && method->is_string()) {
    const auto it = removed_threads.find(method->get<std::string>());
    const auto threads = params->find("threads");
    if (it != removed_threads.end() && threads != params->end() && *threads == it->second) params->erase(threads);
  }
  for (auto& [k, v] : params->items()) {
    if (!v.is_string()) continue;
    const std::string s = v.get<std::string>();
    if (s.find_first_of(".eE") == std::string::npos) continue;
    char* end = nullptr;
    errno = 0;
    const double d = std::strtod(s.c_str(), &end);
    if (s.empty() || errno != 0 || *end != '\0' || !std::isfinite(d)) continue;
    ParamValue x;
    x.type = ParamType::real;
    x.real = d;
    v = x.canonical();
  }
}

}  // namespace

json parse_result(const std::string& text, const std::string& file) {
  json r = parse_json_input(text, file);
  ResultSchema::get().validate(r, file);
  migrate_params(r);
  return r;
}

ResultSet load_result_set(const std::string& path) {
  ResultSet set;
  set.path = path;
  std::error_code ec;
  const fs::path p(path);
  if (!fs::exists(p, ec)) throw file_error(path, "no such file or folder");
  if (fs::is_directory(p, ec)) {
    const fs::path dir = fs::is_directory(p / "runs", ec) ? p / "runs" : p;
    fs::directory_iterator it(dir, ec), end;
    if (ec) throw file_error(dir.string(), "cannot list folder: " + ec.message());
    for (; it != end; it.increment(ec)) {
      if (ec) throw file_error(dir.string(), "cannot list folder: " + ec.message());
      if (it->path().extension() == ".json" && !fs::is_directory(it->path(), ec)) set.files.push_back(it->path().string());
    }
    if (set.files.empty()) throw file_error(dir.string(), "no result files (*.json): not a result folder?");
    std::sort(set.files.begin(), set.files.end());
  } else {
    set.files.push_back(path);
  }
  for (auto& f : set.files) set.results.push_back(read_result_file(f));
  return set;
}

}  // namespace bvhbench
