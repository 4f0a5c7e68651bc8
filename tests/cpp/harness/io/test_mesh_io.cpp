// Mesh readers: every good fixture loads with the right triangles and coordinates, every malformed
// one is rejected with an InputError naming the file and the problem, every real mesh loads, and
// write_ply round-trips. Fixtures are made by tests/fixtures/meshes/make_fixtures.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/mesh_reader.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/sha256.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

std::string fixture(const std::string& name) { return std::string(BVHBENCH_FIXTURES_DIR) + "/meshes/" + name; }

using Tri = std::array<std::uint32_t, 3>;

/// The shape every good PLY fixture describes: a unit square (quad) and a triangle over its
/// first edge, fan-triangulated.
const std::vector<Tri> kSquareAndTri = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}};

void expect_square_and_tri(const Mesh& m, bool float_coords, std::uint64_t polygons = 2) {
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.triangles, kSquareAndTri);
  EXPECT_EQ(m.file.polygons, polygons);
  EXPECT_EQ(m.vertices[0], Vec3d(0, 0, 0));
  EXPECT_EQ(m.vertices[1], Vec3d(1, 0, 0));
  EXPECT_EQ(m.vertices[2], Vec3d(1, 1, 0));
  EXPECT_EQ(m.vertices[3], Vec3d(0, 1, 0));
  if (float_coords)
    EXPECT_EQ(m.vertices[4], Vec3d(double(0.1f), double(0.2f), double(0.3f)));
  else
    EXPECT_EQ(m.vertices[4], Vec3d(0.1, 0.2, 0.3));
  EXPECT_EQ(m.sha256, sha256_file(m.path));
}

/// Loads fixture `name` expecting an InputError whose message names the file and contains
/// `problem`.
void expect_rejected(const std::string& name, const std::string& problem) {
  expect_input_error([&] { load_mesh(fixture(name)); }, name, problem);
}

std::string temp_path(const std::string& name) { return testing::TempDir() + "bvhbench_mesh_io_" + name; }

/// The integer types of the PLY spec with their sizes.
struct IntType {
  const char* name;
  int size;
  bool is_signed;
};
const IntType kIntTypes[] = {{"char", 1, true},  {"uchar", 1, false}, {"short", 2, true},  {"ushort", 2, false},
                             {"int", 4, true},   {"uint", 4, false},  {"int8", 1, true},   {"uint8", 1, false},
                             {"int16", 2, true}, {"uint32", 4, false}};

/// A binary PLY with the five vertices of the fixtures and one `tristrips` item of `strip`
/// (-1 written as every bit set, whatever the type).
std::string strip_ply(const std::vector<long long>& strip, const IntType& count, const IntType& index, bool big) {
  std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                  "element tristrips 1\nproperty list " + count.name + " " + index.name +
                  " vertex_indices\nend_header\n";
  const float xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.1f, 0.2f, 0.3f}};
  for (auto& v : xyz)
    for (float c : v) put_float(s, c, big);
  put_bytes(s, strip.size(), count.size, big);
  for (long long i : strip) put_bytes(s, std::uint64_t(i), index.size, big);
  return s;
}

/// What the fixtures' strips give: the square and the triangle, the first started at vertex 1.
const std::vector<Tri> kStripSquareAndTri = {{1, 2, 0}, {0, 2, 3}, {0, 1, 4}};

}  // namespace

// ---- good files ----

TEST(MeshIo, AsciiPlyWithExtraPropertiesListsAndElements) {
  expect_square_and_tri(load_mesh(fixture("good_ascii.ply")), true);
}

TEST(MeshIo, BinaryLittleEndianDoubleUshortIndices) {
  expect_square_and_tri(load_mesh(fixture("good_binary_le_double.ply")), false);
}

TEST(MeshIo, BinaryBigEndianFloatUintIndicesAfterAnotherElement) {
  expect_square_and_tri(load_mesh(fixture("good_binary_be.ply")), true);
}

TEST(MeshIo, BinaryBigEndianDoubleUcharIndices) {
  expect_square_and_tri(load_mesh(fixture("good_binary_be_uchar.ply")), false);
}

TEST(MeshIo, ObjFaceFormsNegativeIndicesContinuationAndPolygon) {
  const Mesh m = load_mesh(fixture("good.obj"));
  ASSERT_EQ(m.vertices.size(), 7u);
  EXPECT_EQ(m.vertices[1], Vec3d(1, 0, 0));  // the w is ignored
  EXPECT_EQ(m.vertices[2], Vec3d(1, 1, 0));  // colour extras are ignored
  EXPECT_EQ(m.vertices[4], Vec3d(0.1, 0.2, 0.3));
  EXPECT_EQ(m.vertices[6], Vec3d(2, 1, 0));
  const std::vector<Tri> expected = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {0, 1, 4}, {1, 5, 6}, {1, 6, 2}, {1, 2, 3}};
  EXPECT_EQ(m.triangles, expected);
  EXPECT_EQ(m.file.polygons, 4u);
}

TEST(MeshIo, CrlfLineEndings) {
  for (const char* name : {"good_crlf.obj", "good_crlf.ply"}) {
    SCOPED_TRACE(name);
    const Mesh m = load_mesh(fixture(name));
    ASSERT_EQ(m.vertices.size(), 3u);
    EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}}));
    EXPECT_EQ(m.vertices[2], Vec3d(0, 1, 0));
  }
}

TEST(MeshIo, DegenerateAndDuplicateTrianglesAreKept) {
  const Mesh m = load_mesh(fixture("degenerate.obj"));
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 1, 2}, {0, 0, 0}}));
}

TEST(MeshIo, FormatIsSniffedWhenTheExtensionIsUnknown) {
  const std::string ply = temp_path("sniff.mesh"), obj = temp_path("sniff.txt");
  write_file_bytes(ply, read_file_bytes(fixture("good_binary_be.ply")));
  write_file_bytes(obj, "# obj\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_square_and_tri([&] { Mesh m = load_mesh(ply); return m; }(), true);
  EXPECT_EQ(load_mesh(obj).triangles.size(), 1u);
  std::remove(ply.c_str());
  std::remove(obj.c_str());
  for (const char* stl : {"good_binary.stl", "good_ascii.stl"}) {
    SCOPED_TRACE(stl);
    const std::string path = temp_path(std::string(stl) + ".dat");
    write_file_bytes(path, read_file_bytes(fixture(stl)));
    expect_square_and_tri(load_mesh(path), true, 3);
    std::remove(path.c_str());
  }
  for (const char* off : {"good.off", "good_coff.off", "good_modelnet.off"}) {  // good.off starts with a comment
    SCOPED_TRACE(off);
    const std::string path = temp_path(std::string(off) + ".dat");
    write_file_bytes(path, read_file_bytes(fixture(off)));
    expect_square_and_tri(load_mesh(path), false);
    std::remove(path.c_str());
  }
}

TEST(MeshIo, ExtensionIsCaseInsensitive) {
  const std::string path = temp_path("upper.OBJ");
  write_file_bytes(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(load_mesh(path).triangles.size(), 1u);
  std::remove(path.c_str());
}

// Every count type and index type of the PLY spec, in both byte orders, through both the fast
// and the generic binary paths (triangles, then a quad that leaves the fast path).
TEST(MeshIo, BinaryPlyEveryIntegerTypeAndByteOrder) {
  const auto put = [](std::string& s, std::uint64_t v, int size, bool big) { put_bytes(s, v, size, big); };
  for (bool big : {false, true})
    for (const IntType& ct : kIntTypes)
      for (const IntType& it : kIntTypes) {
        SCOPED_TRACE(std::string(big ? "BE " : "LE ") + ct.name + " " + it.name);
        std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                        " 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 3\nproperty list " + ct.name + " " + it.name +
                        " vertex_indices\nend_header\n";
        const float xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.1f, 0.2f, 0.3f}};
        for (auto& v : xyz)
          for (float c : v) {
            std::uint32_t u;
            std::memcpy(&u, &c, 4);
            put(s, u, 4, big);
          }
        const std::vector<std::vector<int>> faces = {{0, 1, 4}, {0, 1, 2, 3}, {4, 3, 2}};
        for (const auto& f : faces) {
          put(s, f.size(), ct.size, big);
          for (int i : f) put(s, std::uint64_t(i), it.size, big);
        }
        const std::string path = temp_path("types.ply");
        write_file_bytes(path, s);
        const Mesh m = load_mesh(path);
        EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 4}, {0, 1, 2}, {0, 2, 3}, {4, 3, 2}}));
        EXPECT_EQ(m.vertices[4], Vec3d(double(0.1f), double(0.2f), double(0.3f)));
        std::remove(path.c_str());
      }
}

// An integer coordinate in ASCII PLY is a value of its declared type, as in binary: whole and in
// range (the largest 64-bit values included, which round up when read as double); anything else
// is refused, naming the value, the type and the property.
TEST(MeshIo, AsciiPlyIntegerCoordinatesAreValuesOfTheirType) {
  const auto ply = [](const std::string& x_type, const std::string& x) {
    return "ply\nformat ascii 1.0\nelement vertex 3\nproperty " + x_type +
           " x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
           "end_header\n" + x + " 0 0\n0 1 0\n0 0 1\n3 0 1 2\n";
  };
  EXPECT_EQ(load_mesh_bytes(ply("uchar", "255"), "m.ply").vertices[0].x, 255.0);
  EXPECT_EQ(load_mesh_bytes(ply("char", "-128"), "m.ply").vertices[0].x, -128.0);
  EXPECT_EQ(load_mesh_bytes(ply("int", "-2147483648"), "m.ply").vertices[0].x, -2147483648.0);
  EXPECT_EQ(load_mesh_bytes(ply("uint64", "18446744073709551615"), "m.ply").vertices[0].x, 18446744073709551616.0);
  EXPECT_EQ(load_mesh_bytes(ply("int64", "-9223372036854775808"), "m.ply").vertices[0].x, -9223372036854775808.0);
  EXPECT_EQ(load_mesh_bytes(ply("short", "7.0"), "m.ply").vertices[0].x, 7.0);
  expect_input_error([&] { load_mesh_bytes(ply("uchar", "256"), "m.ply"); }, "m.ply",
                     "line 10 (vertex 0): '256' is not a value of type uint8 (property 'x')");
  expect_input_error([&] { load_mesh_bytes(ply("uint", "-1"), "m.ply"); }, "m.ply", "'-1' is not a value of type uint32");
  expect_input_error([&] { load_mesh_bytes(ply("int", "1.5"), "m.ply"); }, "m.ply", "'1.5' is not a value of type int32");
  expect_input_error([&] { load_mesh_bytes(ply("int16", "32768"), "m.ply"); }, "m.ply", "'32768' is not a value of type int16");
  expect_input_error([&] { load_mesh_bytes(ply("int", "nan"), "m.ply"); }, "m.ply", "has a NaN coordinate");
}

// ---- triangle strips ----

TEST(MeshIo, TristripsBigEndianWithExtraVertexProperties) {
  const Mesh m = load_mesh(fixture("good_tristrips_be.ply"));
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.vertices[4], Vec3d(double(0.1f), double(0.2f), double(0.3f)));
  EXPECT_EQ(m.triangles, kStripSquareAndTri);
  EXPECT_EQ(m.file.format, "ply");
  EXPECT_EQ(m.file.variant, "binary_big_endian");
  EXPECT_EQ(m.file.strips, 2u);               // 1 2 0 3 | 0 0 0 1 4
  EXPECT_EQ(m.file.strip_joins_dropped, 2u);  // (0,0,0) and (0,0,1)
  EXPECT_EQ(m.file.polygons, 0u);
  EXPECT_EQ(m.sha256, sha256_file(m.path));
}

TEST(MeshIo, TristripsAsciiBesideAFaceElement) {
  const Mesh m = load_mesh(fixture("good_tristrips_ascii.ply"));
  EXPECT_EQ(m.triangles, kSquareAndTri);  // the face's two triangles first, in element order
  EXPECT_EQ(m.file.polygons, 1u);
  EXPECT_EQ(m.file.polygons_triangulated, 1u);
  EXPECT_EQ(m.file.strips, 1u);  // the -1 at both ends and the empty list make no strip
  EXPECT_EQ(m.file.strip_joins_dropped, 0u);
}

// Triangle k of a strip is (v[k], v[k+1], v[k+2]), every odd one flipped to (v[k+1], v[k], v[k+2]):
// on a planar zigzag every triangle then faces the same way (+z).
TEST(MeshIo, TristripsKeepTheWindingAlongAStrip) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                  "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n";
  for (int i = 0; i < 4; ++i) s += std::to_string(i) + " 0 0\n" + std::to_string(i) + " 1 0\n";
  s += "8 0 1 2 3 4 5 6 7\n";  // bottom and top row alternate: (0,1,2) (2,1,3) (2,3,4) ...
  const Mesh m = load_mesh_bytes(s, "zigzag.ply", "ply");
  ASSERT_EQ(m.triangles.size(), 6u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{2, 1, 3}));
  EXPECT_EQ(m.triangles[2], (Tri{2, 3, 4}));
  EXPECT_EQ(m.triangles[3], (Tri{4, 3, 5}));
  for (const Tri& t : m.triangles) {
    const Vec3d n = cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
    EXPECT_LT(n.z, 0.0) << t[0] << " " << t[1] << " " << t[2];  // (0,1,2) turns clockwise seen from +z
  }
  EXPECT_EQ(m.file.strips, 1u);
}

// Only a repeated index makes a join: three distinct collinear vertices are a (degenerate) triangle
// like any other, kept.
TEST(MeshIo, TristripsKeepDegenerateTrianglesOfDistinctVertices) {
  const Mesh m = load_mesh_bytes("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement tristrips 1\nproperty list int int vertex_indices\n"
                                 "end_header\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n", "collinear.ply");
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}}));
  EXPECT_EQ(m.file.strip_joins_dropped, 0u);
}

// Every count type and index type, both byte orders: -1 (every bit set, so 255 for uchar) restarts.
TEST(MeshIo, TristripsEveryIntegerTypeAndByteOrder) {
  for (bool big : {false, true})
    for (const IntType& ct : kIntTypes)
      for (const IntType& it : kIntTypes) {
        SCOPED_TRACE(std::string(big ? "BE " : "LE ") + ct.name + " " + it.name);
        const Mesh m = load_mesh_bytes(strip_ply({1, 2, 0, 3, -1, 0, 0, 0, 1, 4}, ct, it, big), "types.ply");
        EXPECT_EQ(m.triangles, kStripSquareAndTri);
        EXPECT_EQ(m.file.strips, 2u);
        EXPECT_EQ(m.file.strip_joins_dropped, 2u);
      }
}

// A strip item before the vertex element and a face element after it: triangles in file order,
// the same on every pass.
TEST(MeshIo, TristripsBeforeTheVerticesAndFacesAfter) {
  const std::string s = "ply\nformat ascii 1.0\nelement tristrips 1\nproperty list int int vertex_indices\n"
                        "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                        "4 1 2 0 3\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.1 0.2 0.3\n3 0 1 4\n";
  auto reader = MeshReader::open_bytes(s, "order.ply", "ply");
  reader->read_vertices([](std::uint64_t, const Vec3d*, std::size_t) {});
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<Tri> got;
    reader->read_triangles([&](std::uint64_t first, const Triangle* t, std::size_t n) {
      EXPECT_EQ(first, got.size());
      got.insert(got.end(), t, t + n);
    });
    EXPECT_EQ(got, kStripSquareAndTri) << "pass " << pass;
    EXPECT_EQ(reader->info().strips, 1u);
    EXPECT_EQ(reader->info().polygons, 1u);
  }
}

// One strip of 3M indices (12 MB, more than the 8 MiB read buffer): streamed in pieces, never
// held whole; every triangle of a grid of rows joined by degenerate triangles.
TEST(MeshIo, LongStripCrossesBufferBoundaries) {
  const std::uint32_t cols = 1000, rows = 1500;  // (rows + 1) x cols vertices
  std::vector<long long> strip;
  for (std::uint32_t r = 0; r < rows; ++r) {
    if (r > 0) {  // join: repeat the last index and the next row's first, keeping even parity
      strip.push_back(strip.back());
      strip.push_back(std::int64_t(r) * cols);
    }
    for (std::uint32_t c = 0; c < cols; ++c) {
      strip.push_back(std::int64_t(r) * cols + c);
      strip.push_back(std::int64_t(r + 1) * cols + c);
    }
  }
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string((rows + 1) * cols) +
                  "\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\n"
                  "property list uint uint vertex_indices\nend_header\n";
  for (std::uint32_t r = 0; r <= rows; ++r)
    for (std::uint32_t c = 0; c < cols; ++c) {
      put_float(s, float(c), false);
      put_float(s, float(r), false);
      put_float(s, 0.f, false);
    }
  put_bytes(s, strip.size(), 4, false);
  for (long long i : strip) put_bytes(s, std::uint64_t(i), 4, false);
  ASSERT_GT(s.size(), std::size_t(12) << 20);
  const std::string path = temp_path("long_strip.ply");
  write_file_bytes(path, s);
  const Mesh m = load_mesh(path);
  std::remove(path.c_str());
  EXPECT_EQ(m.triangles.size(), std::size_t(rows) * (2 * cols - 2));
  EXPECT_EQ(m.file.strip_joins_dropped, std::size_t(rows - 1) * 4);
  std::size_t facing_down = 0;
  for (const Tri& t : m.triangles) {
    const Vec3d n = cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
    if (n.z < 0) ++facing_down;
  }
  EXPECT_EQ(facing_down, m.triangles.size()) << "one orientation along the whole strip";
  // The last triangle is an odd one of its row: (v[k+1], v[k], v[k+2]).
  EXPECT_EQ(m.triangles.back(), (Tri{rows * cols - 1, (rows + 1) * cols - 2, (rows + 1) * cols - 1}));
  EXPECT_EQ(m.sha256, sha256_hex(s.data(), s.size()));
}

// ---- STL ----

TEST(MeshIo, BinaryStlWithSolidHeaderIsBinary) {
  const Mesh m = load_mesh(fixture("good_binary.stl"));
  expect_square_and_tri(m, true, 3);
  EXPECT_FALSE(std::signbit(m.vertices[0].x)) << "the first corner's +0 is kept; the later -0 welds to it";
  EXPECT_EQ(m.file.format, "stl");
  EXPECT_EQ(m.file.variant, "binary");
  EXPECT_EQ(m.file.corners, 9u);
}

TEST(MeshIo, AsciiStlTwoSolidsMixedCaseSplitLines) {
  const Mesh m = load_mesh(fixture("good_ascii.stl"));
  expect_square_and_tri(m, true, 3);
  EXPECT_EQ(m.file.variant, "ascii");
  EXPECT_EQ(m.file.solids, 2u);
  EXPECT_EQ(m.file.corners, 9u);
}

// Welding is by value, exactly: -0.0 and 0.0 are one vertex (the first corner's sign is kept),
// a coordinate one float ulp away is another vertex.
TEST(MeshIo, StlWeldsEqualValuesOnly) {
  Mesh m;
  const float up = std::nextafter(1.0f, 2.0f);
  m.vertices = {{-0.0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.0, -0.0, 0}, {double(up), 0, 0}};
  m.triangles = {{0, 1, 2}, {3, 4, 2}};
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    const Mesh r = load_mesh_bytes(ascii ? stl_ascii_bytes(m) : stl_binary_bytes(m), "weld.stl");
    ASSERT_EQ(r.vertices.size(), 4u);
    EXPECT_TRUE(std::signbit(r.vertices[0].x));
    EXPECT_EQ(r.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 3, 2}}));
    EXPECT_EQ(r.vertices[3].x, double(up));
  }
}

// ASCII STL numbers are rounded to float32 like binary STL stores them: both read the same mesh,
// which is the mesh's float32 values welded (here a closed torus: every vertex shared).
TEST(MeshIo, AsciiAndBinaryStlReadTheSameMesh) {
  const Mesh m = torus(24, 12, 1.0, 0.35);
  const Mesh want = stl_canonical(m);
  const Mesh a = load_mesh_bytes(stl_ascii_bytes(m), "torus.stl"), b = load_mesh_bytes(stl_binary_bytes(m), "t.stl");
  EXPECT_EQ(a.vertices, want.vertices);
  EXPECT_EQ(a.triangles, want.triangles);
  EXPECT_EQ(b.vertices, want.vertices);
  EXPECT_EQ(b.triangles, want.triangles);
  EXPECT_EQ(b.vertices.size(), m.vertices.size()) << "a closed torus's corners weld to its vertices";
}

TEST(MeshIo, AsciiStlPolygonLoopIsFanTriangulated) {
  const Mesh m = load_mesh_bytes("solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                 "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid q\n", "quad.stl");
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
  EXPECT_EQ(m.file.polygons, 1u);
  EXPECT_EQ(m.file.polygons_triangulated, 1u);
}

// 200,000 facets (10 MB, more than the read buffer), read three times: the same triangles from
// the weld table each pass, which the reader reports as resident.
TEST(MeshIo, LargerBinaryStlThreePasses) {
  const Mesh m = torus(500, 200);
  const std::string bytes = stl_binary_bytes(m, "binary");
  ASSERT_GT(bytes.size(), std::size_t(9) << 20);
  const std::string path = temp_path("big.stl");
  write_file_bytes(path, bytes);
  auto reader = MeshReader::open(path);
  std::vector<Vec3d> v;
  reader->read_vertices([&](std::uint64_t, const Vec3d* p, std::size_t n) { v.insert(v.end(), p, p + n); });
  EXPECT_EQ(v.size(), m.vertices.size());
  EXPECT_GT(reader->resident_bytes(), 12 * v.size()) << "the weld table: coordinates and index";
  const Mesh want = stl_canonical(m);
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<Tri> t;
    reader->read_triangles([&](std::uint64_t, const Triangle* p, std::size_t n) { t.insert(t.end(), p, p + n); });
    EXPECT_EQ(t, want.triangles) << "pass " << pass;
  }
  EXPECT_EQ(reader->sha256(), sha256_file(path));
  std::remove(path.c_str());
}

// ---- OFF ----

TEST(MeshIo, OffVariants) {
  const struct { const char* file; const char* variant; } cases[] = {
      {"good.off", "OFF"},           // comments and blank lines anywhere, counts on the next line
      {"good_coff.off", "COFF"},     // counts on the keyword line, vertex and face colours
      {"good_modelnet.off", "OFF"},  // "OFF5 2 0": ModelNet's counts glued to the keyword
      {"good_stcnoff.off", "STCNOFF"},
      {"good_noff.off", "nOFF"}};    // a dimension line (3)
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    const Mesh m = load_mesh(fixture(c.file));
    expect_square_and_tri(m, false);
    EXPECT_EQ(m.file.format, "off");
    EXPECT_EQ(m.file.variant, c.variant);
    EXPECT_EQ(m.file.polygons_triangulated, 1u);
  }
}

TEST(MeshIo, OffAndObjReadTheSameDoublesAsTheMesh) {
  const Mesh m = torus(16, 8);
  for (const std::string& bytes : {off_bytes(m), off_bytes(m, "COFF"), obj_bytes(m)}) {
    const Mesh r = load_mesh_bytes(bytes, "torus", "");
    EXPECT_EQ(r.vertices, m.vertices);
    EXPECT_EQ(r.triangles, m.triangles);
  }
}

// ---- the reader: bytes in memory, several passes ----

const char* const kGoodFixtures[] = {"good_ascii.ply",        "good_binary_le_double.ply", "good_binary_be.ply",
                                     "good_binary_be_uchar.ply", "good_tristrips_be.ply", "good_tristrips_ascii.ply",
                                     "good.obj",              "good_crlf.obj",             "good_crlf.ply",
                                     "good_binary.stl",       "good_ascii.stl",            "good.off",
                                     "good_coff.off",         "good_modelnet.off",         "good_stcnoff.off",
                                     "good_noff.off"};

// load_mesh_bytes is the file reader's code: the same mesh, hash and file info for every fixture,
// with the format given or sniffed.
TEST(MeshIo, BytesInMemoryReadAsTheFile) {
  for (const char* name : kGoodFixtures) {
    SCOPED_TRACE(name);
    const Mesh a = load_mesh(fixture(name));
    const std::string bytes = read_file_bytes(fixture(name));
    for (const std::string& format : {std::string(name), std::string()}) {
      const Mesh b = load_mesh_bytes(bytes, "mem", format);
      EXPECT_EQ(b.path, "mem");
      EXPECT_EQ(b.vertices, a.vertices);
      EXPECT_EQ(b.triangles, a.triangles);
      EXPECT_EQ(b.sha256, a.sha256);
      EXPECT_EQ(b.file.format, a.file.format);
      EXPECT_EQ(b.file.variant, a.file.variant);
      EXPECT_EQ(b.file.polygons, a.file.polygons);
      EXPECT_EQ(b.file.strip_joins_dropped, a.file.strip_joins_dropped);
    }
  }
  expect_input_error([] { load_mesh_bytes("ply\n", "mem", "xyz"); }, "mem", "unknown mesh format 'xyz'");
}

// Every pass of read_triangles delivers the same triangles in the same chunks.
TEST(MeshIo, TrianglePassesRepeat) {
  for (const char* name : kGoodFixtures) {
    SCOPED_TRACE(name);
    auto reader = MeshReader::open(fixture(name));
    reader->read_vertices([](std::uint64_t, const Vec3d*, std::size_t) {});
    std::vector<Tri> first;
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<Tri> t;
      reader->read_triangles([&](std::uint64_t at, const Triangle* p, std::size_t n) {
        EXPECT_EQ(at, t.size());
        t.insert(t.end(), p, p + n);
      });
      if (pass == 0) first = t;
      EXPECT_EQ(t, first) << "pass " << pass;
    }
    EXPECT_EQ(reader->num_triangles(), first.size());
    EXPECT_EQ(reader->sha256(), sha256_file(fixture(name)));
  }
}

TEST(MeshIo, WritePlyRoundTripsBinaryAndAscii) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.1, -2.5, 1e-3}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 3, 3}};
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    const std::string path = temp_path(ascii ? "rt_ascii.ply" : "rt_binary.ply");
    write_ply(path, m, ascii);
    const Mesh r = load_mesh(path);
    EXPECT_EQ(r.triangles, m.triangles);
    ASSERT_EQ(r.vertices.size(), m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(r.vertices[i][k], double(float(m.vertices[i][k])));
    EXPECT_EQ(r.file.polygons, 3u);
    EXPECT_TRUE(leftover_temporaries(path).empty()) << "the temporary file was left behind";
    std::remove(path.c_str());
  }
}

TEST(MeshIo, LargerBinaryMeshCrossesBufferBoundaries) {
  // ~2.5 MB of faces: several buffer refills, faces split across them.
  Mesh m;
  const std::uint32_t nv = 50000, nt = 200000;
  for (std::uint32_t i = 0; i < nv; ++i) m.vertices.emplace_back(i * 0.5, -double(i), 1.0 / (i + 1));
  for (std::uint32_t i = 0; i < nt; ++i) m.triangles.push_back({i % nv, (i * 7 + 1) % nv, (i * 13 + 5) % nv});
  const std::string path = temp_path("larger.ply");
  write_ply(path, m);
  const Mesh r = load_mesh(path);
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_EQ(r.vertices[nv - 1], Vec3d(Vec3<float>(m.vertices[nv - 1])));
  EXPECT_EQ(r.sha256, sha256_file(path));
  std::remove(path.c_str());
}

TEST(MeshIo, BoundsAndAverageEdgeLength) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {3, 0, 0}, {0, 4, 0}, {-1, 7, 2}};
  m.triangles = {{0, 1, 2}};
  const Box3d b = m.bounds();
  EXPECT_EQ(b.lo, Vec3d(-1, 0, 0));
  EXPECT_EQ(b.hi, Vec3d(3, 7, 2));  // unreferenced vertices count too
  EXPECT_DOUBLE_EQ(m.average_edge_length(), 4.0);  // (3 + 5 + 4) / 3
  EXPECT_EQ(Mesh().average_edge_length(), 0.0);
  EXPECT_TRUE(Mesh().bounds().empty());
}

// ---- real meshes ----

TEST(MeshIo, RealMeshesLoad) {
  const struct { const char* name; std::size_t vertices, triangles; } meshes[] = {
      {"stanford-bunny.obj", 35947, 69451}, {"spot.obj", 2930, 5856},
      {"cow.obj", 2903, 5804},              {"fandisk.obj", 6475, 12946},
      {"homer.obj", 6002, 12000},           {"rocker-arm.obj", 10044, 20088}};
  for (const auto& mm : meshes) {
    SCOPED_TRACE(mm.name);
    const std::string path = std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + mm.name;
    const Mesh m = load_mesh(path);
    EXPECT_EQ(m.vertices.size(), mm.vertices);
    EXPECT_EQ(m.triangles.size(), mm.triangles);
    EXPECT_EQ(m.sha256, sha256_file(path));
    EXPECT_GT(m.average_edge_length(), 0.0);
  }
}

// ---- the streamed summary ----

/// The same facts whichever way they were read: the mesh loaded whole, or one streamed pass.
void expect_same_summary(const MeshSummary& a, const MeshSummary& b) {
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.sha256, b.sha256);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.bounds.lo, b.bounds.lo);
  EXPECT_EQ(a.bounds.hi, b.bounds.hi);
}

// Every fixture, good or malformed, in every format: the summary of a streamed pass is the loaded
// mesh's, and a file load_mesh refuses is refused with the same message.
TEST(MeshSummary, StreamedPassMatchesTheLoadedMeshOnEveryFixture) {
  const auto [good, bad] = expect_reads_every_fixture_as_load_mesh(
      [](const std::string& path) { summarize_mesh(path); },
      [](const std::string& path, const Mesh& m) {
        expect_same_summary(summarize_mesh(path), m.summary());
        EXPECT_EQ(m.summary().triangles, m.num_triangles());
      });
  EXPECT_GT(good, 10);
  EXPECT_GT(bad, 30);
}

TEST(MeshSummary, RealMeshes) {
  for (const char* name : {"stanford-bunny.obj", "rocker-arm.obj"}) {
    const std::string path = std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + name;
    SCOPED_TRACE(path);
    const MeshSummary s = summarize_mesh(path);
    expect_same_summary(s, load_mesh(path).summary());
    EXPECT_EQ(s.sha256, sha256_file(path));
  }
}

// ---- malformed files ----

TEST(MeshIoRejects, MissingFile) { expect_rejected("no_such_file.ply", "not found"); }
TEST(MeshIoRejects, Directory) {
  try {
    load_mesh(std::string(BVHBENCH_FIXTURES_DIR) + "/meshes");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("directory"), std::string::npos) << e.what();
  }
}
TEST(MeshIoRejects, BadMagic) { expect_rejected("bad_magic.ply", "bad magic"); }
TEST(MeshIoRejects, UnknownPlyFormat) { expect_rejected("bad_format.ply", "binary_middle_endian"); }
TEST(MeshIoRejects, HeaderWithoutEnd) { expect_rejected("bad_no_end_header.ply", "end_header"); }
TEST(MeshIoRejects, UnknownFormat) { expect_rejected("bad_unknown.xyz", "unknown mesh format"); }
TEST(MeshIoRejects, BinaryDataInObj) { expect_rejected("bad_binary.obj", "binary data"); }

TEST(MeshIoRejects, TruncatedBinary) { expect_rejected("bad_truncated.ply", "truncated"); }
TEST(MeshIoRejects, TruncatedInFaces) { expect_rejected("bad_truncated_faces.ply", "truncated: the file ends in face 1 of 2"); }
TEST(MeshIoRejects, LyingHeaderFailsFastWithoutAllocating) {
  expect_rejected("bad_lying_header.ply", "4000000000 vertices");
}
TEST(MeshIoRejects, HugeListLength) { expect_rejected("bad_huge_list.ply", "truncated"); }
TEST(MeshIoRejects, CountMismatchFewerFaces) { expect_rejected("bad_count_mismatch.ply", "counts do not match"); }
TEST(MeshIoRejects, CountMismatchExtraData) { expect_rejected("bad_extra_data.ply", "counts do not match"); }
TEST(MeshIoRejects, AsciiLineWithTooFewValues) { expect_rejected("bad_too_few_values.ply", "line 11 (vertex 1): too few values"); }
TEST(MeshIoRejects, ObjVertexWithTooFewCoordinates) { expect_rejected("bad_too_few_coords.obj", "vertex 2 has 2 coordinates"); }

TEST(MeshIoRejects, IndexOutOfRangePly) {
  expect_rejected("bad_index_out_of_range.ply", "face 0 has vertex index 7 out of range");
}
TEST(MeshIoRejects, NegativeIndexBinaryPly) {
  expect_rejected("bad_index_binary.ply", "face 0 has vertex index -1 out of range");
}
TEST(MeshIoRejects, IndexOutOfRangeObj) {
  expect_rejected("bad_index_out_of_range.obj", "face 2 has vertex index 9 out of range");
}
TEST(MeshIoRejects, NegativeIndexOutOfRangeObj) {
  expect_rejected("bad_negative_index.obj", "face 1 has vertex index -4 out of range");
}
TEST(MeshIoRejects, ZeroIndexObj) { expect_rejected("bad_zero_index.obj", "vertex index 0 out of range"); }

TEST(MeshIoRejects, NanCoordinatePly) { expect_rejected("bad_nan.ply", "vertex 1 has a NaN coordinate"); }
TEST(MeshIoRejects, NanCoordinateObj) { expect_rejected("bad_nan.obj", "vertex 3 has a NaN coordinate"); }
TEST(MeshIoRejects, InfiniteCoordinatePly) { expect_rejected("bad_inf.ply", "vertex 2 has an infinite coordinate"); }
TEST(MeshIoRejects, InfiniteCoordinateObj) { expect_rejected("bad_inf.obj", "vertex 2 has an infinite coordinate"); }

TEST(MeshIoRejects, EmptyMeshPly) { expect_rejected("bad_empty.ply", "no triangles"); }
TEST(MeshIoRejects, EmptyMeshObj) { expect_rejected("bad_empty.obj", "no triangles"); }
TEST(MeshIoRejects, EmptyFile) { expect_rejected("bad_empty_file.obj", "no triangles"); }

TEST(MeshIoRejects, TwoVertexFacePly) { expect_rejected("bad_two_vertex_face.ply", "face 0 has 2 vertices"); }
TEST(MeshIoRejects, TwoVertexFaceObj) { expect_rejected("bad_two_vertex_face.obj", "face 1 has 2 vertices"); }

TEST(MeshIoRejects, TristripIndexOutOfRange) {
  expect_rejected("bad_tristrips_index.ply", "tristrips 0 has vertex index 9 out of range (the header declares 4 vertices)");
}
TEST(MeshIoRejects, TristripTruncated) {
  expect_rejected("bad_tristrips_truncated.ply", "truncated: the file ends in tristrips 0 of 1");
}
TEST(MeshIoRejects, TristripsOfJoinsOnly) { expect_rejected("bad_tristrips_only_joins.ply", "no triangles"); }
TEST(MeshIoRejects, TristripFloatIndices) {
  expect_input_error([] { load_mesh_bytes("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                          "property float z\nelement tristrips 1\nproperty list int float vertex_indices\n"
                                          "end_header\n0\n", "f.ply"); },
                     "f.ply", "strip vertex indices have a floating-point type");
}

TEST(MeshIoRejects, StlTruncatedBinary) {
  expect_rejected("bad_truncated.stl", "truncated: the binary STL header declares 3 facets (84 + 50 x 3 = 234 bytes) but the file has 214 bytes");
}
TEST(MeshIoRejects, StlBinaryExtraData) { expect_rejected("bad_extra_data.stl", "but the file has 244 bytes (counts do not match the data)"); }
TEST(MeshIoRejects, StlBinaryHeaderSolidButWrongSize) {
  expect_rejected("bad_binary_with_solid_header.stl",
                  "binary data in an ASCII STL (if this is a binary STL: the binary STL header declares 3 facets");
}
TEST(MeshIoRejects, StlNanCoordinate) { expect_rejected("bad_nan.stl", "facet 1 vertex 2 has a NaN coordinate"); }
TEST(MeshIoRejects, StlInfiniteCoordinate) { expect_rejected("bad_inf.stl", "facet 0 vertex 1 has an infinite coordinate"); }
TEST(MeshIoRejects, StlTwoVertexFacet) { expect_rejected("bad_two_vertex_facet.stl", "facet 0 has 2 vertices (a face needs at least 3)"); }
TEST(MeshIoRejects, StlGarbageNumber) { expect_rejected("bad_garbage_number.stl", "line 5: '1.0abc' is not a number"); }
TEST(MeshIoRejects, StlTruncatedAscii) { expect_rejected("bad_truncated_ascii.stl", "truncated: the file ends in facet 0"); }
TEST(MeshIoRejects, StlNoEndsolid) { expect_rejected("bad_no_endsolid.stl", "truncated: the file ends in solid 0 after 1 facet (no 'endsolid')"); }
TEST(MeshIoRejects, StlUnknownKeyword) { expect_rejected("bad_keyword.stl", "line 8: unexpected 'endfacett' (expected 'endfacet')"); }
TEST(MeshIoRejects, EmptyMeshStl) {
  expect_rejected("bad_empty.stl", "no triangles (the file has no facets)");
  expect_rejected("bad_empty_binary.stl", "no triangles (the file has no facets)");
}

TEST(MeshIoRejects, OffRefusedVariants) {
  expect_rejected("bad_4off.off", "'4OFF' has homogeneous coordinates (x y z w), which are not read");
  expect_rejected("bad_noff_dim4.off", "'nOFF' of dimension '4': only 3D vertices are read");
  expect_rejected("bad_binary.off", "binary OFF ('OFF BINARY') is not read");
  expect_rejected("bad_keyword.off", "not an OFF file: 'OFX' is not an OFF keyword");
}
TEST(MeshIoRejects, OffCounts) {
  expect_rejected("bad_counts.off", "line 2: bad counts line '3 x 0'");
  expect_rejected("bad_truncated.off", "truncated: the file ends in face 1 of 2 declared in the header (counts do not match the data)");
  expect_rejected("bad_lying_header.off", "truncated: the header declares 4000000000 vertices and 4000000000 faces");
  expect_rejected("bad_extra_data.off", "line 7: more data after the last face than the header declares (counts do not match the data)");
}
TEST(MeshIoRejects, OffValues) {
  expect_rejected("bad_index_out_of_range.off", "line 6: face 0 has vertex index 7 out of range (the header declares 3 vertices)");
  expect_rejected("bad_nan.off", "vertex 1 has a NaN coordinate");
  expect_rejected("bad_inf.off", "vertex 2 has an infinite coordinate");
  expect_rejected("bad_two_vertex_face.off", "line 6: face 0 has 2 vertices (a face needs at least 3)");
  expect_rejected("bad_empty.off", "no triangles (the file has no faces)");
  expect_rejected("bad_garbage_number.off", "line 4 (vertex 1): 'zero' is not a number");
  expect_rejected("bad_too_few_values.off", "line 4 (vertex 1): too few values (x y z expected)");
  expect_rejected("bad_too_many_values.off", "line 4 (vertex 1): more values than x y z and a normal, a colour and texture coordinates ('10' left over)");
}

TEST(MeshIoRejects, GarbageNumberPly) { expect_rejected("bad_garbage_number.ply", "'zero' is not a number"); }
TEST(MeshIoRejects, GarbageNumberObj) { expect_rejected("bad_garbage_number.obj", "'1.0abc' is not a number"); }
TEST(MeshIoRejects, GarbageIndexObj) { expect_rejected("bad_garbage_index.obj", "'two' is not a vertex reference"); }

// The same words for the same kind of problem, in every format that can have it.
TEST(MeshIoRejects, EveryKindOfProblemInTheSameWordsInEveryFormat) {
  const struct { const char* problem; std::vector<const char*> files; } kinds[] = {
      {"file not found", {"no_such_file.ply", "no_such_file.obj", "no_such_file.stl", "no_such_file.off"}},
      {"unknown mesh format", {"bad_unknown.xyz"}},
      {"truncated", {"bad_truncated.ply", "bad_tristrips_truncated.ply", "bad_truncated.stl", "bad_truncated_ascii.stl",
                     "bad_truncated.off"}},
      {"counts do not match the data", {"bad_count_mismatch.ply", "bad_extra_data.ply", "bad_extra_data.stl",
                                        "bad_extra_data.off", "bad_truncated.off"}},
      {"bytes follow the header", {"bad_lying_header.ply", "bad_lying_header.off"}},
      {"out of range", {"bad_index_out_of_range.ply", "bad_index_binary.ply", "bad_tristrips_index.ply",
                        "bad_index_out_of_range.obj", "bad_index_out_of_range.off"}},
      {"has a NaN coordinate", {"bad_nan.ply", "bad_nan.obj", "bad_nan.stl", "bad_nan.off"}},
      {"has an infinite coordinate", {"bad_inf.ply", "bad_inf.obj", "bad_inf.stl", "bad_inf.off"}},
      {"has 2 vertices (a face needs at least 3)", {"bad_two_vertex_face.ply", "bad_two_vertex_face.obj",
                                                     "bad_two_vertex_facet.stl", "bad_two_vertex_face.off"}},
      {"no triangles", {"bad_empty.ply", "bad_tristrips_only_joins.ply", "bad_empty.obj", "bad_empty_file.obj",
                        "bad_empty.stl", "bad_empty_binary.stl", "bad_empty.off"}},
      {"is not a number", {"bad_garbage_number.ply", "bad_garbage_number.obj", "bad_garbage_number.stl",
                           "bad_garbage_number.off"}}};
  for (const auto& k : kinds)
    for (const char* file : k.files) expect_rejected(file, k.problem);
}

// Prefixes of good files are rejected cleanly or read consistently (never a crash or a hang).
TEST(MeshIoRejects, EveryTruncationOfABinaryFile) {
  for (const char* name : {"good_binary_le_double.ply", "good_binary_be.ply", "good_ascii.ply", "good.obj",
                           "good_tristrips_be.ply", "good_tristrips_ascii.ply", "good_binary.stl",
                           "good_ascii.stl", "good.off", "good_coff.off"}) {
    const std::string bytes = read_file_bytes(fixture(name));
    const std::string ext = std::string(name).substr(std::string(name).rfind('.'));
    const std::string path = temp_path("prefix" + ext);
    for (std::size_t n = 0; n < bytes.size(); n += 3) {
      write_file_bytes(path, bytes.substr(0, n));
      try {
        const Mesh m = load_mesh(path);
        // An OBJ or an ASCII prefix can still be a valid, smaller mesh; it must be consistent.
        for (const auto& t : m.triangles)
          for (auto i : t) ASSERT_LT(i, m.vertices.size()) << name << " prefix " << n;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
      }
    }
    std::remove(path.c_str());
  }
}
