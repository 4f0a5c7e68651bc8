#include "harness/run/summary_csv.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "harness/util/errors.hpp"
#include "harness/util/json_path.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) {
    if (c == '"') o += '"';
    o += c == '\n' ? ' ' : c;
  }
  return o + "\"";
}

std::string num(const json& j) {
  if (j.is_null()) return "";
  if (j.is_number_integer() || j.is_number_unsigned()) return std::to_string(j.get<long long>());
  if (j.is_number()) {
    std::ostringstream os;
    os.precision(9);
    os << j.get<double>();
    return os.str();
  }
  if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
  if (j.is_string()) return j.get<std::string>();
  return "";
}


const std::vector<std::string> kCounterColumns = {"nodes_visited", "triangles_tested", "planes_tested",
                                                   "bytes_read", "cache_hit_rate"};

}  // namespace

std::vector<std::string> summary_header() {
  std::vector<std::string> h = {"job_id", "method", "params_key", "mesh", "triangles", "query_kind", "n",
                                "query", "status", "message", "build_s", "structure_bytes",
                                "bytes_per_triangle", "peak_rss_bytes", "query_rss_bytes", "qps_median",
                                "qps_min", "qps_max", "p50_ns", "p99_ns", "p999_ns", "max_ns",
                                "over_deadline", "inside_wrong_rate", "inside_wrong_far",
                                "dist_abs_err_max", "dist_rel_err_p99", "normal_err_p99_deg"};
  for (auto& c : kCounterColumns) h.push_back("c_" + c);
  return h;
}

std::vector<std::string> summary_row(const json& r) {
  auto mesh_name = [&]() -> std::string {
    json n = json_at(r, {"job", "mesh", "name"});
    if (n.is_string()) return n;
    json p = json_at(r, {"job", "mesh", "path"});
    return p.is_string() ? fs::path(p.get<std::string>()).stem().string() : "";
  };
  json tris = json_at(r, {"job", "mesh", "triangles"});
  json sb = json_at(r, {"build", "structure_bytes"});
  std::string bpt;
  if (tris.is_number() && sb.is_number() && tris.get<double>() > 0) bpt = num(json(sb.get<double>() / tris.get<double>()));
  std::vector<std::string> row = {
      num(json_at(r, {"job", "id"})), num(json_at(r, {"job", "method"})), num(json_at(r, {"job", "params_key"})), mesh_name(),
      num(tris), num(json_at(r, {"job", "queries", "kind"})), num(json_at(r, {"job", "queries", "n"})),
      num(json_at(r, {"job", "query"})), num(json_at(r, {"status"})), num(json_at(r, {"message"})),
      num(json_at(r, {"build", "seconds"})), num(sb), bpt, num(json_at(r, {"memory", "peak_rss_bytes"})),
      num(json_at(r, {"memory", "query_rss_bytes"})), num(json_at(r, {"queries", "throughput_qps", "median"})),
      num(json_at(r, {"queries", "throughput_qps", "min"})), num(json_at(r, {"queries", "throughput_qps", "max"})),
      num(json_at(r, {"queries", "latency_ns", "p50"})), num(json_at(r, {"queries", "latency_ns", "p99"})),
      num(json_at(r, {"queries", "latency_ns", "p999"})), num(json_at(r, {"queries", "latency_ns", "max"})),
      num(json_at(r, {"queries", "over_deadline"})), num(json_at(r, {"accuracy", "inside", "rate"})),
      num(json_at(r, {"accuracy", "inside", "wrong_far"})),
      num(json_at(r, {"accuracy", "distance", "abs_error", "max"})),
      num(json_at(r, {"accuracy", "distance", "rel_error", "p99"})),
      num(json_at(r, {"accuracy", "distance", "normal_angle_deg", "p99"}))};
  for (auto& c : kCounterColumns) row.push_back(num(json_at(r, {"counters", c.c_str()})));
  for (auto& s : row) s = csv_escape(s);
  return row;
}

void write_summary_csv(const std::string& path, const std::vector<json>& results) {
  std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw file_error(path, "cannot write");
    auto line = [&](const std::vector<std::string>& cells) {
      for (std::size_t i = 0; i < cells.size(); ++i) f << (i ? "," : "") << cells[i];
      f << "\n";
    };
    line(summary_header());
    for (auto& r : results) line(summary_row(r));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw file_error(path, "cannot rename into place");
}

}  // namespace bvhbench
