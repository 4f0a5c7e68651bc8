// What the C++ tests share: the meshes they build in code or load from ../shared/meshes, the
// query points they sample, file helpers, and the check of a float32 method (cgal_aabb, embree)
// against brute_force. Header-only; every helper is deterministic (fixed seeds), so a test's
// cases are the same on every run.
//
// Units: coordinates are the mesh's own units; tolerances written "of the diagonal" are relative
// to the diagonal of the mesh's bounding box.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <ostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/method_support.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench::test {

// ---- files ----

/// A fresh temporary directory (PREFIX_XXXXXX under the system's), removed with its contents.
struct TmpDir {
  std::filesystem::path p;
  explicit TmpDir(const std::string& prefix = "bvhbench_test") {
    std::string t = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    EXPECT_NE(::mkdtemp(t.data()), nullptr);
    p = t;
  }
  ~TmpDir() {
    std::error_code ec;
    std::filesystem::remove_all(p, ec);
  }
  TmpDir(const TmpDir&) = delete;
  TmpDir& operator=(const TmpDir&) = delete;
  std::string file(const std::string& n) const { return (p / n).string(); }
};

/// Path of `file` (e.g. "cow.obj") in the shared mesh folder ../shared/meshes.
inline std::string shared_mesh_path(const std::string& file) {
  return std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + file;
}

/// The shared mesh `file`, as load_mesh reads it (double coordinates, triangulated).
inline Mesh load_shared_mesh(const std::string& file) { return load_mesh(shared_mesh_path(file)); }

/// A test-name fragment for a mesh file: the name before its first '.', each '-' replaced by
/// `dash` ("" drops them). Test names must be [A-Za-z0-9_].
inline std::string mesh_stem(const std::string& file, const std::string& dash) {
  const std::string stem = file.substr(0, file.find('.'));
  std::string out;
  for (char c : stem) {
    if (c == '-')
      out += dash;
    else
      out += c;
  }
  return out;
}

/// All bytes of the file at `path` ("" when it cannot be read).
inline std::string read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

/// The temporaries an atomic writer of `path` left in its folder (AtomicOutputFile names them
/// "PATH.tmp.<random>"; older writers used "PATH.tmp"): file names, sorted.
inline std::vector<std::string> leftover_temporaries(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  const std::string prefix = p.filename().string() + ".tmp";
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.compare(0, prefix.size(), prefix) == 0) out.push_back(n);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// Replaces the file at `path` with exactly `bytes`.
inline void write_file_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), std::streamsize(bytes.size()));
}

/// Runs `f` expecting an InputError whose message names `name` (a file or source) and contains
/// `problem`; any other outcome is a test failure.
inline void expect_input_error(const std::function<void()>& f, const std::string& name,
                               const std::string& problem) {
  SCOPED_TRACE(name);
  try {
    f();
    ADD_FAILURE() << name << ": no error";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << "expected '" << problem << "' in: " << msg;
  }
}

/// Every mesh fixture, good or malformed, in every format (fixtures/meshes): `reader(path)` must
/// read what load_mesh reads (`good(path, mesh)` checks it) and refuse what load_mesh refuses, with
/// the same message. Returns {good, refused}, for the caller to check that both kinds were seen.
inline std::pair<int, int> expect_reads_every_fixture_as_load_mesh(
    const std::function<void(const std::string&)>& reader,
    const std::function<void(const std::string&, const Mesh&)>& good) {
  int loaded = 0, refused = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BVHBENCH_FIXTURES_DIR) + "/meshes")) {
    if (!entry.is_regular_file()) continue;
    const std::string path = entry.path().string();
    SCOPED_TRACE(path);
    std::string load_error;
    Mesh m;
    try {
      m = load_mesh(path);
    } catch (const InputError& e) {
      load_error = e.what();
    }
    if (load_error.empty()) {
      good(path, m);
      ++loaded;
      continue;
    }
    try {
      reader(path);
      ADD_FAILURE() << "read what load_mesh refused: " << load_error;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), load_error);
    }
    ++refused;
  }
  return {loaded, refused};
}

// ---- one mesh in every format (the bytes of a file) ----
//
// Coordinates are written as the shortest text that reads back as the same double (to_chars),
// so a text file reads the same values as a binary one.

/// Shortest decimal text that reads back as exactly `v`.
inline std::string exact_text(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

/// Appends the low `size` bytes of v, little endian (or big endian).
inline void put_bytes(std::string& s, std::uint64_t v, int size, bool big = false) {
  for (int i = 0; i < size; ++i) s += char((v >> (8 * (big ? size - 1 - i : i))) & 0xff);
}
inline void put_float(std::string& s, float f, bool big = false) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  put_bytes(s, u, 4, big);
}

/// A binary STL of m's triangles: float32 corners, zero normals; `header` (at most 80 bytes)
/// starts the 80-byte header ("solid ..." by default: the classic trap).
inline std::string stl_binary_bytes(const Mesh& m, const std::string& header = "solid bvhbench test") {
  std::string s = header;
  s.resize(80, ' ');
  put_bytes(s, m.triangles.size(), 4);
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) put_float(s, 0.f);
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) put_float(s, float(m.vertices[t[c]][k]));
    put_bytes(s, 0, 2);
  }
  return s;
}

/// An ASCII STL of m's triangles (each coordinate as the text of its float32 value).
inline std::string stl_ascii_bytes(const Mesh& m) {
  std::string s = "solid test\n";
  for (const auto& t : m.triangles) {
    s += "facet normal 0 0 0\n outer loop\n";
    for (int c = 0; c < 3; ++c) {
      s += "  vertex";
      for (int k = 0; k < 3; ++k) s += " " + exact_text(double(float(m.vertices[t[c]][k])));
      s += "\n";
    }
    s += " endloop\nendfacet\n";
  }
  return s + "endsolid test\n";
}

/// An OFF file of m: `keyword` ("OFF", "COFF": then a colour after each vertex and face).
inline std::string off_bytes(const Mesh& m, const std::string& keyword = "OFF") {
  const bool colour = keyword == "COFF";
  std::string s = keyword + "\n# written by a test\n" + std::to_string(m.vertices.size()) + " " +
                  std::to_string(m.triangles.size()) + " 0\n";
  for (const Vec3d& v : m.vertices)
    s += exact_text(v.x) + " " + exact_text(v.y) + " " + exact_text(v.z) + (colour ? " 255 128 0 255\n" : "\n");
  for (const auto& t : m.triangles)
    s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
         (colour ? " 0.5 0.5 0.5\n" : "\n");
  return s;
}

/// An OBJ file of m (`v` and `f` lines).
inline std::string obj_bytes(const Mesh& m) {
  std::string s = "# written by a test\n";
  for (const Vec3d& v : m.vertices) s += "v " + exact_text(v.x) + " " + exact_text(v.y) + " " + exact_text(v.z) + "\n";
  for (const auto& t : m.triangles)
    s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n";
  return s;
}

/// A binary big-endian PLY that stores m's triangles as one `tristrips` item, the way scans
/// store them: float x y z plus `confidence` and `intensity` per vertex, the triangles in order,
/// every fifth one after a -1 restart and the others after a join (the previous strip's last
/// index and the next triangle's first, repeated: triangles with a repeated index, dropped by
/// the reader). Each triangle starts at an even position of its strip, so it reads back as it
/// is, corner for corner. Returns the bytes; `joins` (optional) gets the join count.
inline std::string tristrip_ply_bytes(const Mesh& m, std::uint64_t* joins = nullptr) {
  std::vector<std::int64_t> strip;
  std::size_t since_restart = 0;  // entries since the last restart
  std::uint64_t j = 0;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& t = m.triangles[i];
    if (i > 0 && i % 5 == 0) {
      strip.push_back(-1);
      since_restart = 0;
    } else if (i > 0) {
      const std::int64_t last = strip.back();
      // last, a, a (and one more a if needed for an even position): every window is a join.
      std::size_t n = 3 + ((since_restart + 2) % 2 == 0 ? 0 : 1);
      strip.push_back(last);
      for (std::size_t k = 1; k < n; ++k) strip.push_back(t[0]);
      since_restart += n;
      j += n + 1;  // the windows that end in the pushed entries, and the one ending in t[1]
      strip.push_back(t[1]);
      strip.push_back(t[2]);
      since_restart += 2;
      continue;
    }
    for (int k = 0; k < 3; ++k) strip.push_back(t[k]);
    since_restart += 3;
  }
  if (joins) *joins = j;
  std::string s = "ply\nformat binary_big_endian 1.0\ncomment a strip of joined and restarted triangles\n"
                  "element vertex " + std::to_string(m.vertices.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty float confidence\n"
                  "property float intensity\nelement tristrips 1\nproperty list int int vertex_indices\n"
                  "end_header\n";
  for (const Vec3d& v : m.vertices) {
    for (int k = 0; k < 3; ++k) put_float(s, float(v[k]), true);
    put_float(s, 0.75f, true);
    put_float(s, 0.5f, true);
  }
  put_bytes(s, strip.size(), 4, true);
  for (std::int64_t v : strip) put_bytes(s, std::uint64_t(v), 4, true);
  return s;
}

/// m as an STL gives it back: each coordinate rounded to float32, corners welded exactly (equal
/// values, so -0 == 0), vertices renumbered in order of first use by the triangles
/// (unreferenced ones gone). Written in any of the formats above, it reads back the same.
inline Mesh stl_canonical(const Mesh& m) {
  Mesh r;
  std::map<std::array<float, 3>, std::uint32_t> id;
  for (const auto& t : m.triangles) {
    std::array<std::uint32_t, 3> nt{};
    for (int c = 0; c < 3; ++c) {
      std::array<float, 3> key;
      for (int k = 0; k < 3; ++k) key[k] = float(m.vertices[t[c]][k]) + 0.0f;  // -0 + 0 = +0
      auto it = id.find(key);
      if (it == id.end()) {
        it = id.emplace(key, std::uint32_t(r.vertices.size())).first;
        const Vec3d& v = m.vertices[t[c]];
        r.vertices.emplace_back(double(float(v.x)), double(float(v.y)), double(float(v.z)));
      }
      nt[c] = it->second;
    }
    r.triangles.push_back(nt);
  }
  return r;
}

// ---- meshes made in code ----

/// Unit cube [0,1]^3, outward-oriented: 8 vertices, 12 triangles. Triangles 0-1 are the bottom
/// (z = 0) face, 2-3 the top (z = 1) face.
inline Mesh unit_cube() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                 {2, 3, 7}, {2, 7, 6}, {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
  return m;
}

/// The unit cube without its top (z = 1) face: an open cup, 10 triangles, 4 boundary edges.
inline Mesh open_cup() {
  Mesh m = unit_cube();
  m.triangles.erase(m.triangles.begin() + 2, m.triangles.begin() + 4);
  return m;
}

/// 2n query points around `m`, drawn from `rng` in this order: n uniform in its vertices' box grown
/// by 10 % of its extent on each side, then n within 1 % of the box's diagonal (per coordinate) of
/// random vertices.
inline std::vector<Vec3d> box_and_near_vertex_points(const Mesh& m, std::size_t n, std::mt19937_64& rng) {
  Box3d b;
  for (const Vec3d& v : m.vertices) b.add(v);
  const Vec3d e = b.extent();
  std::uniform_real_distribution<double> u(-0.1, 1.1), s(-1, 1);
  std::vector<Vec3d> q;
  for (std::size_t i = 0; i < n; ++i) q.push_back({b.lo.x + u(rng) * e.x, b.lo.y + u(rng) * e.y, b.lo.z + u(rng) * e.z});
  const double h = 0.01 * b.diagonal();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& v = m.vertices[rng() % m.vertices.size()];
    q.push_back({v.x + h * s(rng), v.y + h * s(rng), v.z + h * s(rng)});
  }
  return q;
}

/// A closed torus (procedural), nu x nv quads split in two; `open` drops half of the tube.
inline Mesh torus(int nu, int nv, double R = 1.0, double r = 0.35, bool open = false) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      m.vertices.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto id = [&](int i, int j) { return std::uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < (open ? nu / 2 : nu); ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// The triangle (0,0,0), (1,0,0), (0,1,0): normal +z, an open surface.
inline Mesh one_triangle() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  return m;
}

/// Splits every triangle of `m` into four at its edge midpoints, `levels` times (4^levels times
/// the triangles, orientation kept). A midpoint shared by two triangles is one vertex. With
/// `project_midpoints`, each new midpoint is moved onto the unit sphere as it is made.
inline void subdivide(Mesh& m, int levels, bool project_midpoints) {
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3d p = (m.vertices[a] + m.vertices[b]) * 0.5;
      m.vertices.push_back(project_midpoints ? normalized(p) : p);
      return mid[key] = std::uint32_t(m.vertices.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (auto f : m.triangles) {
      std::uint32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
}

/// Icosphere of radius r centred at the origin: 20 * 4^level triangles, outward, closed. The
/// icosahedron is subdivided flat and every vertex is then projected to radius r.
inline Mesh icosphere(int level, double r = 1.0) {
  Mesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  m.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  subdivide(m, level, false);
  for (auto& v : m.vertices) v = normalized(v) * r;
  return m;
}

/// Unit sphere from an octahedron subdivided `levels` times (8 * 4^levels triangles), outward,
/// each midpoint projected as it is made. Its sha256 is the stand-in "sphere<levels>".
inline Mesh octasphere(int levels) {
  Mesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  subdivide(m, levels, true);
  m.sha256 = "sphere" + std::to_string(levels);
  return m;
}

/// The mesh as the float32 methods hold it: every coordinate rounded to the nearest float32
/// (through round_to_float32's volatile, not a plain `Vec3d(Vec3f(v))`: see there why).
inline Mesh float_rounded(const Mesh& m) {
  Mesh r = m;
  for (auto& v : r.vertices) v = round_to_float32(v);
  return r;
}

// ---- methods ----

/// `spec` (a registry spec, "name:key=value,...") built on `mesh` for `query_type` questions;
/// the rest of the BuildContext is default. Throws what create() or build() throws.
inline std::unique_ptr<Method> build_method(const std::string& spec, const Mesh& mesh, QueryType query_type) {
  auto m = Registry::global().create(spec);
  BuildContext ctx;
  ctx.query_type = query_type;
  m->build(mesh, ctx);
  return m;
}

/// Counters by name.
inline std::map<std::string, std::uint64_t> counter_values(const std::vector<Counter>& counters) {
  std::map<std::string, std::uint64_t> c;
  for (const auto& x : counters) c[x.name] = x.value;
  return c;
}

/// The method's counters by name.
inline std::map<std::string, std::uint64_t> counter_values(const Method& m) { return counter_values(m.counters()); }

/// Resets d's counters, asks the distance of every query (answers ignored), and returns the
/// counters: the work of that one pass.
inline std::vector<Counter> count_distance_pass(Method& d, const std::vector<Vec3d>& queries) {
  d.reset_counters();
  for (const Vec3d& p : queries) (void)d.distance(p);
  return d.counters();
}

/// Distance from p to triangle t of m (>= 0, the mesh's units).
inline double distance_to_triangle(const Mesh& m, std::int64_t t, const Vec3d& p) {
  const auto& f = m.triangles[std::size_t(t)];
  return norm(closest_point_on_triangle(p, m.vertices[f[0]], m.vertices[f[1]], m.vertices[f[2]]) - p);
}

// ---- query points ----

/// n points uniform in box b enlarged by `margin` times its extent on every side (margin 0.1:
/// the box grown by 10% each way), drawn from `rng` (three draws a point).
inline std::vector<Vec3d> random_points(std::mt19937_64& rng, const Box3d& b, double margin, int n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3d lo = b.lo - b.extent() * margin, ext = b.extent() * (1 + 2 * margin);
  std::vector<Vec3d> p(std::size_t(std::max(n, 0)));
  for (auto& q : p) q = lo + Vec3d(u(rng) * ext.x, u(rng) * ext.y, u(rng) * ext.z);
  return p;
}

/// The same with a fresh mt19937_64 seeded with `seed`.
inline std::vector<Vec3d> random_points(const Box3d& b, double margin, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  return random_points(rng, b, margin, n);
}

/// n_random points uniform in the mesh's box enlarged by 10%, then n_near points near the
/// surface: a uniform point of a random triangle moved along its normal by up to 2% of the
/// diagonal either way. Needs at least one triangle.
inline std::vector<Vec3d> sample_queries(const Mesh& m, int n_random, int n_near, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0, 1);
  const double diag = m.bounds().diagonal();
  std::vector<Vec3d> q = random_points(rng, m.bounds(), 0.1, n_random);
  std::uniform_int_distribution<std::size_t> tri(0, m.triangles.size() - 1);
  for (int i = 0; i < n_near; ++i) {
    const auto& t = m.triangles[tri(rng)];
    double s = u01(rng), r = u01(rng);
    if (s + r > 1) s = 1 - s, r = 1 - r;
    const Vec3d a = m.vertices[t[0]], bb = m.vertices[t[1]], c = m.vertices[t[2]];
    const Vec3d on = a + (bb - a) * s + (c - a) * r;
    q.push_back(on + triangle_normal(a, bb, c) * ((u01(rng) * 2 - 1) * 0.02 * diag));
  }
  return q;
}

/// A haptic-like ordered path of n points: a random walk with Gaussian steps of 0.4% of the
/// diagonal per axis, starting 1% of the diagonal off the first triangle's first vertex.
inline std::vector<Vec3d> sample_path(const Mesh& m, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const double diag = m.bounds().diagonal();
  std::vector<Vec3d> q;
  Vec3d p = m.vertices[m.triangles[0][0]] + Vec3d(0.01, 0.01, 0.01) * diag;
  for (int i = 0; i < n; ++i) {
    p += Vec3d(g(rng), g(rng), g(rng)) * (0.004 * diag);
    q.push_back(p);
  }
  return q;
}

// ---- a float32 method against brute_force ----
//
// A method that keeps float32 geometry (the contract) is compared with brute_force built on the
// same float32-rounded mesh: both then answer for the same surface.

/// Checks `spec` against brute force (on the float-rounded `input`) at `queries`:
///  - |distance| agrees within 1e-5 of the diagonal, and |closest - p| is |distance| within 1e-9;
///  - the closest triangle is the same, or a tie: brute force's distance to it is the minimum
///    within 1e-9 of the diagonal;
///  - the normal is the closest triangle's face normal within 1e-6;
///  - when `closed`, inside (and the distance's sign) is identical for points farther than 1e-6
///    of the diagonal from the surface. On open meshes parity and the winding number disagree by
///    design: only an answer is required.
/// The method is built twice, once per query type, and reset_path() before the queries.
inline void expect_matches_brute_force(const std::string& spec, const Mesh& input, bool closed,
                                       const std::vector<Vec3d>& queries) {
  const Mesh ref_mesh = float_rounded(input);
  const double diag = ref_mesh.bounds().diagonal();
  auto ref = build_method("brute_force", ref_mesh, QueryType::distance);
  auto dist = build_method(spec, input, QueryType::distance);
  auto ins = build_method(spec, input, QueryType::inside);
  dist->reset_path();
  ins->reset_path();
  int triangle_mismatch = 0, inside_mismatch = 0;
  for (const Vec3d& p : queries) {
    const DistanceResult want = ref->distance(p);
    const DistanceResult got = dist->distance(p);
    SCOPED_TRACE(spec + " at (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                 std::to_string(p.z) + ")");
    ASSERT_GE(got.triangle, 0);
    ASSERT_LT(std::size_t(got.triangle), input.triangles.size());
    EXPECT_NEAR(std::abs(got.distance), std::abs(want.distance), 1e-5 * diag);
    EXPECT_NEAR(norm(got.closest - p), std::abs(got.distance), 1e-9 * diag);
    const double to_got = distance_to_triangle(ref_mesh, got.triangle, p);
    if (got.triangle != want.triangle && std::abs(to_got - std::abs(want.distance)) > 1e-9 * diag)
      ++triangle_mismatch;
    const auto& f = ref_mesh.triangles[std::size_t(got.triangle)];
    const Vec3d n = triangle_normal(ref_mesh.vertices[f[0]], ref_mesh.vertices[f[1]], ref_mesh.vertices[f[2]]);
    EXPECT_NEAR(norm(got.normal - n), 0.0, 1e-6);
    const bool in = ins->inside(p);
    if (closed && std::abs(want.distance) > 1e-6 * diag) {
      const bool want_in = want.distance < 0;
      if (in != want_in) ++inside_mismatch;
      EXPECT_EQ(got.distance < 0, want_in);
    }
  }
  EXPECT_EQ(triangle_mismatch, 0) << spec;
  EXPECT_EQ(inside_mismatch, 0) << spec;
}

/// The `coherent` spec replays the ordered `path` with the same answers as the `plain` one, in
/// two passes (the second after reset_path()): distances within 1e-12 of the diagonal, and a
/// different triangle only if it is a tie within 1e-9 of the diagonal.
inline void expect_coherent_replay_matches(const std::string& plain, const std::string& coherent,
                                           const Mesh& mesh, const std::vector<Vec3d>& path) {
  const Mesh ref_mesh = float_rounded(mesh);
  const double diag = ref_mesh.bounds().diagonal();
  auto a = build_method(plain, mesh, QueryType::distance);
  auto b = build_method(coherent, mesh, QueryType::distance);
  for (int pass = 0; pass < 2; ++pass) {
    a->reset_path();
    b->reset_path();
    for (const Vec3d& p : path) {
      const DistanceResult x = a->distance(p), y = b->distance(p);
      EXPECT_NEAR(x.distance, y.distance, 1e-12 * diag);
      if (x.triangle != y.triangle) {
        EXPECT_NEAR(distance_to_triangle(ref_mesh, y.triangle, p), std::abs(x.distance), 1e-9 * diag);
      }
    }
  }
}

/// One shared mesh of a parameterised test: the file in ../shared/meshes, whether it is closed
/// (inside is then checked), and how many random and near-surface queries to sample.
struct SharedMesh {
  const char* file;
  bool closed;
  int n_random, n_near;
};

/// What --gtest_list_tests and failure messages show for the parameter.
inline void PrintTo(const SharedMesh& sm, std::ostream* os) {
  *os << sm.file << (sm.closed ? " (closed, " : " (open, ") << sm.n_random << " random + " << sm.n_near
      << " near queries)";
}

/// Names a SharedMesh instance by its file: "rocker-arm.obj" -> "rocker_arm".
struct SharedMeshName {
  std::string operator()(const ::testing::TestParamInfo<SharedMesh>& info) const {
    return mesh_stem(info.param.file, "_");
  }
};

/// The shared meshes the float32 methods are checked on, with their query counts.
inline const std::vector<SharedMesh>& float32_method_meshes() {
  static const std::vector<SharedMesh> meshes = {
      {"cow.obj", true, 150, 150},     {"fandisk.obj", true, 150, 150},
      {"homer.obj", true, 150, 150},   {"rocker-arm.obj", true, 150, 150},
      {"spot.obj", false, 150, 150},   {"stanford-bunny.obj", false, 60, 60}};
  return meshes;
}

// ---- a float32 method on degenerate input (the answers are exact) ----

/// One triangle: queries on a vertex, an edge and the face are at distance 0 (within `on_surface`:
/// 1e-15, or what a method computing in float32 arithmetic rounds to) on triangle 0; a point above
/// the face is 3 away with normal +z; a far point's closest point is the vertex at the origin; no
/// point is inside an open surface.
inline void expect_one_triangle_answers(const std::string& spec, double on_surface = 1e-15) {
  const Mesh m = one_triangle();
  auto d = build_method(spec, m, QueryType::distance), in = build_method(spec, m, QueryType::inside);
  for (Vec3d p : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0.5, 0.5, 0}, Vec3d{0.2, 0.2, 0}}) {
    DistanceResult r = d->distance(p);
    EXPECT_NEAR(r.distance, 0.0, on_surface) << spec;
    EXPECT_NEAR(norm(r.closest - p), 0.0, on_surface) << spec;
    EXPECT_EQ(r.triangle, 0);
    (void)in->inside(p);  // on the surface: any answer, but an answer
  }
  DistanceResult r = d->distance({0.25, 0.25, 3});
  EXPECT_NEAR(r.distance, 3.0, 1e-12) << spec;
  EXPECT_NEAR(r.normal.z, 1.0, 1e-12) << spec;
  r = d->distance({-1e6, -1e6, 1e6});
  EXPECT_NEAR(r.distance, std::sqrt(3.0) * 1e6, 1e-6) << spec;
  EXPECT_EQ(r.closest, Vec3d(0, 0, 0)) << spec;
  EXPECT_FALSE(in->inside({0.25, 0.25, 0.5})) << spec;
  EXPECT_FALSE(in->inside({-1e6, -1e6, 1e6})) << spec;
}

/// The unit cube: points on a vertex, an edge and a face are at distance exactly 0 and are their
/// own closest point (inside() must terminate there); inside/outside and signed distances
/// elsewhere, including a far corner.
inline void expect_cube_surface_answers(const std::string& spec) {
  auto d = build_method(spec, unit_cube(), QueryType::distance);
  auto in = build_method(spec, unit_cube(), QueryType::inside);
  for (Vec3d p : {Vec3d{1, 1, 1}, Vec3d{0, 0, 0}, Vec3d{0.5, 0, 0}, Vec3d{0.5, 0.5, 0}}) {
    DistanceResult r = d->distance(p);
    EXPECT_EQ(r.distance, 0.0) << spec;
    EXPECT_EQ(r.closest, p) << spec;
    (void)in->inside(p);  // must terminate
  }
  EXPECT_TRUE(in->inside({0.5, 0.5, 0.5})) << spec;
  EXPECT_TRUE(in->inside({0.999, 0.001, 0.5})) << spec;
  EXPECT_FALSE(in->inside({1e6, 1e6, 1e6})) << spec;
  DistanceResult r = d->distance({0.5, 0.5, 0.2});
  EXPECT_NEAR(r.distance, -0.2, 1e-7) << spec;
  r = d->distance({1e6, 1e6, 1e6});
  EXPECT_NEAR(r.distance, std::sqrt(3.0) * (1e6 - 1), 1e-6) << spec;
  EXPECT_EQ(r.closest, Vec3d(1, 1, 1)) << spec;
}

/// The unit cube plus zero-area triangles (a sliver along an edge, a collapsed one, one with a
/// repeated index): inside stays right; with a duplicate triangle added too, the method matches
/// brute force (as an open mesh) on 40 random + 40 near queries of the cube.
inline void expect_degenerate_triangle_answers(const std::string& spec) {
  Mesh m = unit_cube();
  m.vertices.push_back({0.5, 0, 0});
  m.triangles.push_back({0, 1, 8});
  m.triangles.push_back({3, 3, 3});
  m.triangles.push_back({6, 6, 2});
  Mesh with_duplicates = m;
  with_duplicates.triangles.push_back(m.triangles[2]);  // a duplicate of the top face's half
  // Degenerate triangles alone do not change parity: inside stays right.
  auto in = build_method(spec, m, QueryType::inside);
  EXPECT_TRUE(in->inside({0.5, 0.5, 0.5})) << spec;
  EXPECT_TRUE(in->inside({0.25, 0.1, 0.3})) << spec;
  EXPECT_FALSE(in->inside({0.5, 0.5, 1.5})) << spec;
  const auto q = sample_queries(unit_cube(), 40, 40, 5);
  expect_matches_brute_force(spec, with_duplicates, false, q);
}

/// A mesh of zero-area triangles only (collinear, a point, a repeated index): distance is the
/// distance to the segment, and nothing is inside.
inline void expect_all_degenerate_answers(const std::string& spec) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {3, 3, 3}, {0, 0, 1}};
  auto d = build_method(spec, m, QueryType::distance), in = build_method(spec, m, QueryType::inside);
  DistanceResult r = d->distance({1.5, 1, 0});
  EXPECT_NEAR(r.distance, 1.0, 1e-12) << spec;
  EXPECT_FALSE(in->inside({1, 0.5, 0})) << spec;
  EXPECT_FALSE(in->inside({1, 0, 0})) << spec;
}

}  // namespace bvhbench::test
