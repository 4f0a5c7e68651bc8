// Text files of points (.xyz, .csv; points_text.hpp): every accepted layout gives the points
// bit-identically and in order, and every malformed line is refused with its line number.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "errors.hpp"
#include "points_text.hpp"
#include "query_set.hpp"
#include "sha256.hpp"
#include "test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

const std::vector<Vec3d> kPts = {{0.1, -2, 3.5e-7}, {1e300, -0.0, 5e-324}, {-1.5, 0.25, 12345.678}};

std::vector<Vec3d> read_text(const TmpDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  write_file_bytes(path, text);
  return read_points_text(path);
}

}  // namespace

TEST(PointsText, EveryLayoutGivesTheSamePoints) {
  TmpDir dir;
  const std::vector<std::pair<std::string, std::string>> layouts = {
      {"spaces.xyz", "0.1 -2 3.5e-7\n1e300 -0 5e-324\n-1.5 0.25 12345.678\n"},
      {"tabs_no_final_newline.xyz", "0.1\t-2\t3.5e-7\n1e300\t\t-0\t5e-324\n  -1.5 \t 0.25 12345.678"},
      {"normals.xyz", "0.1 -2 3.5e-7 0 0 1\n1e300 -0 5e-324 0 1 0\n-1.5 0.25 12345.678 1 0 0\n"},
      {"plus_and_exponents.xyz", "+0.1 -2.0e0 35E-8\n1E+300 -0.0 4.9406564584124654e-324\n-15e-1 +.25 12345.678\n"},
      {"commas.csv", "0.1,-2,3.5e-7\n1e300,-0,5e-324\n-1.5,0.25,12345.678\n"},
      {"commas_and_spaces.csv", "0.1 , -2 ,3.5e-7\n 1e300,-0, 5e-324 \n-1.5,\t0.25,12345.678\n"},
      {"header_comments_blank_crlf.csv",
       "\xEF\xBB\xBFx,y,z,label\r\n# a probe path\r\n\r\n0.1,-2,3.5e-7,a\r\n   \r\n1e300,-0,5e-324,  # no label\r\n"
       "-1.5,0.25,12345.678,c # last\r\n# end\r\n"},
      {"header.xyz", "X Y Z\n0.1 -2 3.5e-7\n1e300 -0 5e-324\n-1.5 0.25 12345.678\n"},
  };
  for (const auto& [name, text] : layouts) {
    SCOPED_TRACE(name);
    const std::vector<Vec3d> got = read_text(dir, name, text);
    ASSERT_EQ(got, kPts);
    EXPECT_TRUE(std::signbit(got[1].y)) << "-0 keeps its sign";
  }
}

// 17 significant digits give every double back exactly, in the file's order; a file of several
// MB is read in pieces, so lines straddle the pieces.
TEST(PointsText, SeventeenDigitsRoundTripBitIdentically) {
  TmpDir dir;
  Rng rng(42);
  std::vector<Vec3d> pts(150000);
  std::string text;
  char buf[128];
  for (Vec3d& p : pts) {
    p = Vec3d(rng.uniform(-1e3, 1e3), rng.normal() * 1e-9, std::ldexp(rng.uniform(), int(rng.below(200)) - 100));
    std::snprintf(buf, sizeof buf, "%.17g %.17g\t%.17g\n", p.x, p.y, p.z);
    text += buf;
  }
  ASSERT_GT(text.size(), std::size_t(3) << 20);
  EXPECT_EQ(read_text(dir, "many.xyz", text), pts);
}

TEST(PointsText, EveryMalformedLineIsRefusedWithItsNumber) {
  struct Case {
    std::string name, text, problem;
  };
  const std::vector<Case> cases = {
      {"two.xyz", "1 2 3\n4 5\n", "line 2: 2 values, but the first point (line 1) has 3"},
      {"first_short.xyz", "# c\n1 2\n", "line 2: expected at least 3 values (x y z), found 2"},
      {"more.xyz", "1 2 3\n4 5 6 7\n", "line 2: 4 values, but the first point (line 1) has 3"},
      {"merged.xyz", "1 2 3 0 0 1\n4 5 6 0 0 1 7 8 9 0 0 1\n", "line 2: 12 values, but the first point (line 1) has 6"},
      {"word.xyz", "1 2 3\n4 five 6\n", "line 2: 'five' in column 2 is not a number"},
      {"mixed_first.xyz", "1.0 abc 2\n", "line 1: 'abc' in column 2 is not a number"},
      {"junk.csv", "1,2,3x\n", "line 1: '3x' in column 3 is not a number"},
      {"hex.csv", "x,y,z\n0x1p3,2,3\n", "line 2: '0x1p3' in column 1 is not a number"},
      {"empty_field.csv", "1,2,3\n4,,6\n", "line 2: no value in column 2"},
      {"trailing_comma_short.csv", "1,2,\n", "line 1: no value in column 3"},
      {"semicolons.csv", "1;2;3\n4;5;6\n", "line 2: expected at least 3 values (x y z), found 1"},
      {"one_semicolon_line.csv", "1;2;3\n", "no points after the header (line 1: '1;2;3')"},
      {"nan.xyz", "1 2 3\n\n4 nan 6\n", "line 3: point 1 has a NaN coordinate"},
      {"inf.csv", "x,y,z\n-inf,0,0\n", "line 2: point 0 has an infinite coordinate"},
      {"overflow.xyz", "1 2 1e999\n", "line 1: point 0 has an infinite coordinate"},
      {"second_header.csv", "x,y,z\nx,y,z\n", "line 2: 'x' in column 1 is not a number"},
      {"not_utf8.xyz", "1 2 3\n4 5 \xff\n", "line 2: '\\xFF' in column 3 is not a number"},
      {"long.xyz", "1 2 3\n" + std::string(70000, '1') + "\n", "line 2: longer than 65536 bytes"},
      {"empty.xyz", "", "no points"},
      {"only_comments.csv", "# nothing\n\n  \n", "no points"},
      {"only_header.csv", "# c\nx,y,z\n", "no points after the header (line 2: 'x,y,z')"},
  };
  TmpDir dir;
  for (const Case& c : cases) {
    const std::string path = dir.file(c.name);
    write_file_bytes(path, c.text);
    expect_input_error([&] { read_points_text(path); }, path, c.problem);
  }
  expect_input_error([&] { read_points_text(dir.file("missing.xyz")); }, "missing.xyz", "not found");
}

// ---- query files: which reader, the sidecar, kind `file` ----

TEST(QueryFiles, SidecarPathOfEachForm) {
  EXPECT_EQ(sidecar_path("d/q.npy"), "d/q.json");
  EXPECT_EQ(sidecar_path("d/q.xyz"), "d/q.json");
  EXPECT_EQ(sidecar_path("d/Q.CSV"), "d/Q.json");
  EXPECT_EQ(sidecar_path("d/q.txt"), "d/q.txt.json");
}

TEST(QueryFiles, WithoutSidecarAFileIsKindFile) {
  TmpDir dir;
  const std::string path = dir.file("probe.csv");
  const std::string text = "x,y,z\n0.1,-2,3.5e-7\n1e300,-0,5e-324\n-1.5,0.25,12345.678\n";
  write_file_bytes(path, text);
  const QuerySet q = load_query_set(path);
  EXPECT_EQ(q.points, kPts);
  EXPECT_EQ(q.kind(), "file");
  EXPECT_EQ(q.meta["n"], 3);
  EXPECT_EQ(q.meta["format"], "csv");
  EXPECT_EQ(q.meta["ordered"], true);
  EXPECT_FALSE(q.meta.contains("seed"));
  EXPECT_EQ(q.sha256, sha256_hex(text.data(), text.size()));
  EXPECT_EQ(read_query_points(path), kPts);
}

TEST(QueryFiles, ASidecarIsStillChecked) {
  TmpDir dir;
  const std::string path = dir.file("probe.xyz");
  write_file_bytes(path, "0 0 0\n1 1 1\n");
  write_file_bytes(dir.file("probe.json"), "{\"kind\": \"haptic\", \"n\": 2, \"seed\": 4}");
  EXPECT_EQ(load_query_set(path).kind(), "haptic");
  write_file_bytes(dir.file("probe.json"), "{\"kind\": \"haptic\", \"n\": 3, \"seed\": 4}");
  expect_input_error([&] { load_query_set(path); }, dir.file("probe.json"), "does not match the 2 points");
  write_file_bytes(dir.file("probe.json"), "{\"kind\": \"haptic\", \"n\": 2}");
  expect_input_error([&] { load_query_set(path); }, dir.file("probe.json"), "missing key 'seed'");
  // The runner reads the kind as a string: anything else is refused here, not a JSON type error
  // in the job (found in review; fuzz_query_sidecar confirms it).
  write_file_bytes(dir.file("probe.json"), "{\"kind\": 7, \"n\": 2, \"seed\": 4}");
  expect_input_error([&] { load_query_set(path); }, dir.file("probe.json"), "kind must be a string, not number");
  write_file_bytes(dir.file("probe.json"), "{\"kind\": \"haptic\", \"n\": [[2]], \"seed\": 4}");
  expect_input_error([&] { load_query_set(path); }, dir.file("probe.json"), "n = (array) does not match");
}

TEST(QueryFiles, OtherExtensionsAreRefused) {
  TmpDir dir;
  write_file_bytes(dir.file("q.txt"), "0 0 0\n");
  expect_input_error([&] { load_query_set(dir.file("q.txt")); }, dir.file("q.txt"), "expected a .npy, .xyz or .csv");
  write_file_bytes(dir.file("Q.XYZ"), "0 0 0\n");
  EXPECT_EQ(load_query_set(dir.file("Q.XYZ")).points.size(), 1u);
}
