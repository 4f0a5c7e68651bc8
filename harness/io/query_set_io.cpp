// Query sets on disk: the points file (.npy, .xyz, .csv) and its optional sidecar JSON.
#include "harness/io/query_set_io.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "harness/io/npy.hpp"
#include "harness/io/points_text.hpp"
#include "harness/util/atomic_file.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_input.hpp"
#include "harness/util/sha256.hpp"

namespace bvhbench {

namespace {

/// The extension of `path` in lower case, with its dot ("" if none).
std::string extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool is_points_extension(const std::string& ext) { return ext == ".npy" || ext == ".xyz" || ext == ".csv"; }

}  // namespace

std::string sidecar_path(const std::string& points_path) {
  std::string s = points_path;
  const std::string ext = extension(s);
  if (is_points_extension(ext)) s.resize(s.size() - ext.size());
  return s + ".json";
}

std::vector<Vec3d> read_query_points(const std::string& path) {
  const std::string ext = extension(path);
  if (ext == ".npy") return read_points_npy(path);
  if (ext == ".xyz" || ext == ".csv") return read_points_text(path);
  throw file_error(path, "not a query set: expected a .npy, .xyz or .csv file of points");
}

QuerySet load_query_set(const std::string& points_path) {
  QuerySet q;
  q.path = points_path;
  q.points = read_query_points(points_path);
  q.sha256 = sha256_file(points_path);
  const std::string side = sidecar_path(points_path);
  std::error_code ec;
  if (!std::filesystem::exists(side, ec)) {
    // Points made elsewhere: identified by their hash, replayed in the file's order.
    const std::string ext = extension(points_path);
    q.meta = {{"kind", "file"}, {"n", q.points.size()}, {"format", ext.substr(1)}, {"ordered", true}};
    return q;
  }
  std::ifstream f(side, std::ios::binary);
  if (!f) throw file_error(side, "cannot read the sidecar JSON of query set " + points_path);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  q.meta = parse_sidecar(text, side, points_path, q.points.size());
  return q;
}

nlohmann::json parse_sidecar(std::string_view text, const std::string& side, const std::string& points_path,
                             std::size_t n_points) {
  nlohmann::json meta = parse_json_input(text, side);
  if (!meta.is_object()) throw file_error(side, "sidecar is not a JSON object");
  for (const char* key : {"kind", "n", "seed"})
    if (!meta.contains(key)) throw file_error(side, std::string("missing key '") + key + "'");
  // The runner reads the kind as a string (QuerySet::kind()).
  if (!meta["kind"].is_string())
    throw file_error(side, std::string("kind must be a string, not ") + meta["kind"].type_name());
  const nlohmann::json& n = meta["n"];
  if (!n.is_number_integer() || n.get<long long>() != (long long)n_points)
    throw file_error(side, "n = " + (n.is_number() ? n.dump() : std::string("(") + n.type_name() + ")") +
                               " does not match the " + std::to_string(n_points) + " points of " + points_path);
  return meta;
}

void write_query_set(const std::string& npy_path, const std::vector<Vec3d>& points,
                     nlohmann::json meta) {
  meta["n"] = points.size();
  if (!meta.contains("created_by")) meta["created_by"] = "bvhbench queries";
  write_npy(npy_path, NpyArray::f8_n3(points));
  AtomicOutputFile side(sidecar_path(npy_path));
  side.write(meta.dump(2) + "\n");
  side.commit();
}

}  // namespace bvhbench
