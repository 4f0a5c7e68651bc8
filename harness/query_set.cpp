#include "query_set.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include "commands.hpp"
#include "correctly_rounded.hpp"
#include "errors.hpp"
#include "json_input.hpp"
#include "mesh.hpp"
#include "npy.hpp"
#include "points_text.hpp"
#include "sha256.hpp"

namespace bvhbench {

Box3d QuerySet::bounds() const {
  Box3d b;
  for (auto& p : points) b.add(p);
  return b;
}

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
  std::string side = sidecar_path(npy_path);
  std::string tmp = side + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw file_error(side, "cannot write");
    f << meta.dump(2) << "\n";
    if (!f) throw file_error(side, "write failed");
  }
  if (std::rename(tmp.c_str(), side.c_str()) != 0) throw file_error(side, "cannot rename into place");
}

// ---------------------------------------------------------------------------------------------
// Rng: xoshiro256** seeded by splitmix64 (Blackman and Vigna). Portable and fast.
// ---------------------------------------------------------------------------------------------
namespace {
std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
inline std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
}  // namespace

Rng::Rng(std::uint64_t seed) {
  std::uint64_t x = seed;
  for (auto& s : s_) s = splitmix64(x);
}

std::uint64_t Rng::next() {
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

double Rng::uniform() { return double(next() >> 11) * 0x1.0p-53; }
double Rng::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

double Rng::normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u1 = uniform(), u2 = uniform();
  if (u1 < 1e-300) u1 = 1e-300;
  // Correctly rounded log/sin/cos: the same bits on every machine (correctly_rounded.hpp).
  double r = std::sqrt(-2.0 * correctly_rounded::log(u1));
  double t = 6.283185307179586476925 * u2;
  spare_ = r * correctly_rounded::sin(t);
  has_spare_ = true;
  return r * correctly_rounded::cos(t);
}

std::uint64_t Rng::below(std::uint64_t n) {
  if (n == 0) return 0;
  // Lemire's nearly-divisionless method is overkill here; rejection keeps it unbiased.
  std::uint64_t limit = ~std::uint64_t(0) - (~std::uint64_t(0) % n);
  std::uint64_t x;
  do x = next();
  while (x >= limit);
  return x % n;
}

// ---------------------------------------------------------------------------------------------

std::vector<Vec3d> generate_queries(const Mesh& mesh, const std::string& kind, std::size_t n,
                                    std::uint64_t seed,
                                    const std::map<std::string, double>& given_params,
                                    nlohmann::json* meta) {
  const QueryKind* k = find_query_kind(kind);
  if (!k) {
    std::string known;
    for (auto& q : query_kinds()) known += (known.empty() ? "" : ", ") + q.name;
    throw InputError("unknown query kind '" + kind + "' (known: " + known + ")");
  }
  std::map<std::string, double> params = k->defaults;
  for (auto& [key, v] : given_params) {
    if (!params.count(key)) {
      std::string known;
      for (auto& [d, _] : k->defaults) known += (known.empty() ? "" : ", ") + d;
      throw InputError("query kind '" + kind + "': unknown parameter '" + key + "' (known: " +
                       (known.empty() ? "none" : known) + ")");
    }
    if (!std::isfinite(v)) throw InputError("query kind '" + kind + "': parameter " + key + " is not finite");
    params[key] = v;
  }
  auto pts = k->generate(mesh, n, seed, params);
  if (meta) {
    nlohmann::json m;
    m["kind"] = kind;
    m["n"] = pts.size();
    m["seed"] = seed;
    m["mesh_sha256"] = mesh.sha256;
    m["mesh_path"] = mesh.path;
    m["mesh_triangles"] = mesh.num_triangles();
    m["ordered"] = k->ordered;
    m["params"] = params;
    m["created_by"] = "bvhbench queries";
    *meta = m;
  }
  return pts;
}

const QueryKind* find_query_kind(const std::string& name) {
  for (auto& k : query_kinds())
    if (k.name == name) return &k;
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// `bvhbench queries --mesh M --kind K --n N --seed S --out Q.npy [--param k=v ...]`
// ---------------------------------------------------------------------------------------------
void add_queries_command(CLI::App& app) {
  struct Opts {
    std::string mesh, kind = "random", out;
    std::size_t n = 100000;
    std::uint64_t seed = 1;
    std::vector<std::string> params;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand("queries", "Generate a query set (NAME.npy + NAME.json)");
  cmd->add_option("--mesh", o->mesh, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--kind", o->kind, "Query kind: random, near, haptic, surface ...");
  cmd->add_option("--n", o->n, "Number of points")->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o->seed, "Random seed");
  cmd->add_option("--param", o->params, "Generator parameter key=value (repeatable)");
  cmd->add_option("--out", o->out, "Output .npy (its .json sidecar is written beside it)")->required();
  cmd->callback([o] {
    std::map<std::string, double> given;
    for (auto& kv : o->params) {
      auto eq = kv.find('=');
      if (eq == std::string::npos) throw InputError("--param '" + kv + "': expected key=value");
      char* end = nullptr;
      std::string v = kv.substr(eq + 1);
      double d = std::strtod(v.c_str(), &end);
      if (v.empty() || *end) throw InputError("--param '" + kv + "': value is not a number");
      given[kv.substr(0, eq)] = d;
    }
    if (o->out.size() < 4 || o->out.compare(o->out.size() - 4, 4, ".npy") != 0)
      throw InputError("--out " + o->out + ": must end in .npy");
    // The output folder is checked before the (possibly long) generation: a missing or
    // unwritable folder is bad usage (exit 2), not a failure found minutes later.
    const std::filesystem::path dir = std::filesystem::path(o->out).parent_path().empty()
                                          ? std::filesystem::path(".")
                                          : std::filesystem::path(o->out).parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
      throw InputError("--out " + o->out + ": folder " + dir.string() + " does not exist");
    if (::access(dir.c_str(), W_OK) != 0)
      throw InputError("--out " + o->out + ": folder " + dir.string() + " is not writable");
    Mesh mesh = load_mesh(o->mesh);
    nlohmann::json meta;
    auto pts = generate_queries(mesh, o->kind, o->n, o->seed, given, &meta);
    try {
      write_query_set(o->out, pts, meta);
    } catch (const std::runtime_error& e) {
      throw InputError(e.what());  // names the file and the reason (e.g. no space left)
    }
  });
}

}  // namespace bvhbench
