// Mesh readers: every good fixture loads with the right triangles and coordinates, every malformed
// one is rejected with an InputError naming the file and the problem, every real mesh loads, and
// write_ply round-trips. Fixtures are made by tests/fixtures/meshes/make_fixtures.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "errors.hpp"
#include "mesh.hpp"
#include "sha256.hpp"
#include "test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

std::string fixture(const std::string& name) { return std::string(BVHBENCH_FIXTURES_DIR) + "/meshes/" + name; }

using Tri = std::array<std::uint32_t, 3>;

/// The shape every good PLY fixture describes: a unit square (quad) and a triangle over its
/// first edge, fan-triangulated.
const std::vector<Tri> kSquareAndTri = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}};

void expect_square_and_tri(const Mesh& m, bool float_coords) {
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.triangles, kSquareAndTri);
  EXPECT_EQ(m.file.polygons, 2u);
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
  struct Type { const char* name; int size; };
  const Type types[] = {{"char", 1}, {"uchar", 1}, {"short", 2}, {"ushort", 2}, {"int", 4},
                        {"uint", 4}, {"int8", 1},  {"uint8", 1}, {"int16", 2}, {"uint32", 4}};
  auto put = [](std::string& s, std::uint64_t v, int size, bool big) {
    for (int i = 0; i < size; ++i) s += char((v >> (8 * (big ? size - 1 - i : i))) & 0xff);
  };
  for (bool big : {false, true})
    for (const Type& ct : types)
      for (const Type& it : types) {
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
    std::ifstream tmp(path + ".tmp");
    EXPECT_FALSE(tmp.good()) << "the temporary file was left behind";
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

TEST(MeshIoRejects, GarbageNumberPly) { expect_rejected("bad_garbage_number.ply", "'zero' is not a number"); }
TEST(MeshIoRejects, GarbageNumberObj) { expect_rejected("bad_garbage_number.obj", "'1.0abc' is not a number"); }
TEST(MeshIoRejects, GarbageIndexObj) { expect_rejected("bad_garbage_index.obj", "'two' is not a vertex reference"); }

// Prefixes of good files are rejected cleanly or read consistently (never a crash or a hang).
TEST(MeshIoRejects, EveryTruncationOfABinaryFile) {
  for (const char* name : {"good_binary_le_double.ply", "good_binary_be.ply", "good_ascii.ply", "good.obj"}) {
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
