// Non-UTF-8 bytes in every reader's error paths: the file's name and the bytes quoted from it
// reach the message escaped (printable.hpp), so that it is valid UTF-8 for a terminal and a result
// JSON, and it still names the file. Each file here has a name with a byte 0xFF and contents with
// bytes that are not UTF-8 where the reader quotes them.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "methods/ebp_octree/store/verify.hpp"
#include "harness/core/query_set.hpp"
#include "harness/io/npy.hpp"
#include "harness/io/npz.hpp"
#include "harness/io/points_text.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/zip.hpp"
#include "harness/run/result_set.hpp"
#include "harness/run/suite.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// Checks a refusal's message: printable (so valid UTF-8), naming `path` as printable() writes
/// it, and quoting what it quotes escaped (`escaped`, e.g. "\\xFE"), never the raw bytes.
void expect_printable_refusal(const std::function<void()>& read, const std::string& path, const std::string& escaped) {
  SCOPED_TRACE(printable(path));
  try {
    read();
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(printable(msg), msg) << "not printable: " << printable(msg);
    EXPECT_NO_THROW((void)nlohmann::json(msg).dump()) << printable(msg);
    EXPECT_NE(msg.find(printable(path)), std::string::npos) << msg;
    EXPECT_NE(msg.find(escaped), std::string::npos) << "expected " << escaped << " in: " << msg;
  }
}

/// Writes `bytes` to `path`, then expects `read` to refuse it (expect_printable_refusal).
void expect_refused(const std::string& path, const std::string& bytes, const std::function<void()>& read,
                    const std::string& escaped) {
  write_file_bytes(path, bytes);
  expect_printable_refusal(read, path, escaped);
}

/// An .npy whose header dict is `dict` (padded as NumPy pads it) followed by `data`.
std::string npy_with_header(const std::string& dict, const std::string& data = "") {
  std::string h = dict;
  while ((10 + h.size() + 1) % 64) h += ' ';
  h += '\n';
  std::string out = "\x93NUMPY\x01";
  out += '\0';
  out += char(h.size() & 0xff);
  out += char(h.size() >> 8);
  return out + h + data;
}

}  // namespace

TEST(NonUtf8Messages, NpyHeader) {
  TmpDir dir;
  const std::string path = dir.file("q\xFF.npy");
  expect_refused(path, npy_with_header("{'descr': '<f\xFE" "8', 'fortran_order': False, 'shape': (1, 3), }"),
                 [&] { read_points_npy(path); }, "'<f\\xFE8'");
  expect_refused(path, npy_with_header("{'descr': '<f8', 'fortran_order': False, 'sh\xFE" "pe': (1, 3), }"),
                 [&] { read_points_npy(path); }, "sh\\xFEpe");
  expect_refused(path, "\x93NUMPX\xFE\xFE\xFE\xFE\xFE\xFE", [&] { read_points_npy(path); }, "bad magic");
}

TEST(NonUtf8Messages, NpzEntryNames) {
  TmpDir dir;
  const std::string path = dir.file("t\xFF.npz");
  {
    ZipWriter z(path);
    const std::string bad = "not an npy \xFE";
    z.add_stored("dist\xFE" "ance.npy", {{bad.data(), bad.size()}});
    z.commit();
  }
  expect_printable_refusal([&] { read_npz(path); }, path, "(entry 'dist\\xFEance.npy')");
  {
    ZipWriter z(path);
    const std::string npy = npy_bytes(NpyArray::f8({1.0}));
    z.add_stored("a\xFE.npy", {{npy.data(), npy.size()}});
    z.add_stored("a\xFE.npy", {{npy.data(), npy.size()}});
    z.commit();
  }
  expect_printable_refusal([&] { read_npz(path); }, path, "duplicate entry 'a\\xFE.npy'");
}

TEST(NonUtf8Messages, TextPoints) {
  TmpDir dir;
  const std::string path = dir.file("p\xFF.xyz");
  expect_refused(path, "1 2 3\n4 5 \xFE" "6\n",
                 [&] { read_points_text(path); }, "line 2: '\\xFE6' in column 3 is not a number");
  expect_refused(path, "x\xFE y z\n", [&] { read_points_text(path); }, "(line 1: 'x\\xFE y z')");
}

TEST(NonUtf8Messages, QuerySetSidecar) {
  TmpDir dir;
  const std::string points = dir.file("s\xFF.xyz");
  write_file_bytes(points, "1 2 3\n");
  write_file_bytes(dir.file("s\xFF.json"), "{\"kind\": \"r\xFE\", \"n\": 1, \"seed\": 1}");
  expect_printable_refusal([&] { load_query_set(points); }, dir.file("s\xFF.json"), "malformed JSON");
}

TEST(NonUtf8Messages, SuiteYaml) {
  TmpDir dir;
  const std::string path = dir.file("s\xFF.yml");
  expect_refused(path, "matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    methods: [br\xFEute]\n",
                 [&] { load_suite(path); }, "br\\xFEute");
  expect_refused(path, "matrices:\n  - meshes: [m.ply]\n    queries: [rand\xFEom]\n    methods: [brute_force]\n",
                 [&] { load_suite(path); }, "rand\\xFEom");
  expect_refused(path, "matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    query: [ins\xFEide]\n    methods: [brute_force]\n",
                 [&] { load_suite(path); }, "ins\\xFEide");
}

TEST(NonUtf8Messages, CompareResultFiles) {
  TmpDir dir;
  const std::string path = dir.file("r\xFF.json");
  expect_refused(path, "{\"schema\": \"bvhbench.result/1\", \"status\": \"o\xFEk\"}",
                 [&] { load_result_set(path); }, "malformed JSON");
  expect_refused(path, "{\"schema\": \"bvhbench.result/2\\u00e9\", \"status\": \"ok\"}",
                 [&] { load_result_set(path); }, "unknown result schema");
}

// The mesh readers, each format: a header line (or the keyword line), a keyword and a token of
// the data with bytes 0x80-0xFF, read from a file whose name has a byte 0xFF, and from memory.
namespace {

const char* const kPlyAscii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

struct MeshCase {
  const char* file;     ///< its extension gives the format
  std::string bytes;
  const char* escaped;  ///< what the message quotes
};

const MeshCase kMeshCases[] = {
    {"m\xFF.ply", "ply\nformat asc\xFEii 1.0\nend_header\n", "unknown PLY format 'asc\\xFEii'"},
    {"m\xFF.ply", "ply\nformat ascii 1.0\nelem\x80\xFF vertex 3\nend_header\n",
     "unexpected header line 'elem\\x80\\xFF vertex 3'"},
    {"m\xFF.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty flo\xC3t x\nend_header\n",
     "unknown property type 'flo\\xC3t'"},
    {"m\xFF.ply", std::string(kPlyAscii) + "0 0 0\n1 0 \xFE" "0\n0 1 0\n3 0 1 2\n", "'\\xFE0' is not a number"},
    {"m\xFF.ply", std::string(kPlyAscii) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 \xE9\n", "'\\xE9' is not a vertex index"},
    {"m\xFF.obj", "v 0 0 0\nv 1 0 \xFE\nv 0 1 0\nf 1 2 3\n", "'\\xFE' is not a number"},
    {"m\xFF.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\xA0\n", "'3\\xA0' is not a vertex reference"},
    // A statement OBJ does not know is skipped, whatever its bytes; the vertex data is still read.
    {"m\xFF.obj", "v\xFE 0 0 0\nv 0 0 \x80x\nf 1 2 3\n", "'\\x80x' is not a number"},
    {"m\xFF.stl", "solid a\nfac\xFE" "et normal 0 0 1\n", "unexpected 'fac\\xFEet'"},
    {"m\xFF.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 \xFE\n", "'\\xFE' is not a number"},
    {"m\xFF.stl", "solid a\nfacet normal 0 0 1\nouter \xC3(loop\n", "unexpected '\\xC3(loop'"},
    {"m\xFF.off", "OF\xFE" "F\n3 1 0\n", "not an OFF file: 'OF\\xFEF'"},
    {"m\xFF.off", "OFF\n3 1 \xFE\n", "bad counts line '3 1 \\xFE'"},
    {"m\xFF.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 \x80 0\n3 0 1 2\n", "'\\x80' is not a number"},
    {"m\xFF.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 \xFF\n", "'\\xFF' is not a vertex index"},
};

}  // namespace

TEST(NonUtf8Messages, MeshReaders) {
  TmpDir dir;
  for (const MeshCase& c : kMeshCases) {
    const std::string path = dir.file(c.file);
    SCOPED_TRACE(printable(c.bytes));
    expect_refused(path, c.bytes, [&] { load_mesh(path); }, c.escaped);
    expect_printable_refusal([&] { load_mesh_bytes(c.bytes, path, path); }, path, c.escaped);
  }
}

TEST(NonUtf8Messages, EbpVerify) {
  TmpDir dir;
  const std::string path = dir.file("m\xFF.ebp");
  write_file_bytes(path, std::string(600, '\xFE'));
  const ebp::VerifyReport rep = ebp::verify_store(path);
  ASSERT_EQ(rep.problems.size(), 1u);
  const std::string msg = rep.problems[0].message;
  EXPECT_EQ(printable(msg), msg);
  EXPECT_NE(msg.find(printable(path)), std::string::npos) << msg;
}
