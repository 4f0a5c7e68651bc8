// .npy/.npz: round trips, files made by NumPy (tests/fixtures/npy/make_fixtures.py), malformed
// files, and (when python3 with numpy is present) NumPy reading what we write.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/io/npy.hpp"
#include "harness/io/npz.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

std::string fixture(const std::string& name) { return std::string(BVHBENCH_FIXTURES_DIR) + "/npy/" + name; }
std::string temp_path(const std::string& name) { return testing::TempDir() + "bvhbench_npy_" + name; }

template <class T>
std::vector<T> values(const NpyArray& a) {
  std::vector<T> v(a.size());
  if (!v.empty()) std::memcpy(v.data(), a.data.data(), v.size() * sizeof(T));
  return v;
}

bool have_numpy() {
  static const bool ok = std::system("python3 -c 'import numpy' >/dev/null 2>&1") == 0;
  return ok;
}

/// Checks the arrays of make_fixtures.py's arrays().
void expect_fixture_arrays(const std::map<std::string, NpyArray>& z) {
  ASSERT_EQ(z.size(), 11u);
  const NpyArray& f8 = z.at("f8");
  EXPECT_EQ(f8.dtype, "<f8");
  EXPECT_EQ(f8.shape, (std::vector<std::size_t>{2, 3}));
  const auto v = values<double>(f8);
  EXPECT_EQ(v[0], 0.1);
  EXPECT_EQ(v[3], 1e300);
  EXPECT_TRUE(std::signbit(v[4]));
  EXPECT_EQ(v[5], 5e-324);
  EXPECT_EQ(values<float>(z.at("f4")), (std::vector<float>{1.5f, -0.25f, 3.0f}));
  EXPECT_EQ(values<std::int64_t>(z.at("i8")), (std::vector<std::int64_t>{-1, 0, std::int64_t(1) << 40}));
  EXPECT_EQ(z.at("i4").dtype, "<i4");
  EXPECT_EQ(z.at("i4").shape, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(values<std::int32_t>(z.at("i4")), (std::vector<std::int32_t>{-7, 8}));
  EXPECT_EQ(values<std::uint32_t>(z.at("u4")), (std::vector<std::uint32_t>{4000000000u}));
  EXPECT_EQ(z.at("b1").dtype, "|b1");
  EXPECT_EQ(values<std::uint8_t>(z.at("b1")), (std::vector<std::uint8_t>{1, 0, 1}));
  EXPECT_EQ(z.at("u1").dtype, "|u1");
  EXPECT_EQ(values<std::uint8_t>(z.at("u1")), (std::vector<std::uint8_t>{255, 0}));
  const NpyArray& text = z.at("text");
  EXPECT_EQ(text.dtype, "<U4");
  EXPECT_TRUE(text.shape.empty());
  EXPECT_EQ(text.size(), 1u);
  EXPECT_EQ(text.unicode_value(), "h\xc3\xa9 \xf0\x9f\x99\x82");
  const NpyArray& words = z.at("words");
  EXPECT_EQ(words.dtype, "<U3");
  EXPECT_EQ(words.itemsize(), 12u);
  EXPECT_EQ(words.unicode_value(0), "ab");
  EXPECT_EQ(words.unicode_value(1), "cde");
  EXPECT_EQ(values<double>(z.at("scalar")), (std::vector<double>{2.5}));
  EXPECT_EQ(z.at("empty").shape, (std::vector<std::size_t>{0, 3}));
  EXPECT_TRUE(z.at("empty").data.empty());
}

}  // namespace

// ---- round trips ----

TEST(Npy, RoundTripEveryDtype) {
  std::vector<NpyArray> arrays = {
      NpyArray::f8({1.0, -2.5, 1e-300}), NpyArray::f8_n3({{1, 2, 3}, {4, 5, 6}}),
      NpyArray::i8({-5, 0, 7}),          NpyArray::b1({0, 3, 1}),
      NpyArray::unicode("oracle v1"),    NpyArray::f8({})};
  NpyArray u4;
  u4.dtype = "<u4";
  u4.shape = {2, 2};
  u4.data.resize(16, '\x7f');
  arrays.push_back(u4);
  for (const NpyArray& a : arrays) {
    SCOPED_TRACE(a.dtype);
    const std::string path = temp_path("rt.npy");
    write_npy(path, a);
    const NpyArray r = read_npy(path);
    EXPECT_EQ(r.dtype, a.dtype);
    EXPECT_EQ(r.shape, a.shape);
    EXPECT_EQ(r.data, a.data);
    const std::string bytes = npy_bytes(a);
    EXPECT_EQ(bytes, read_file_bytes(path));
    EXPECT_EQ(bytes.size() % 64, a.data.size() % 64) << "the data is not 64-byte aligned";
    const NpyArray p = parse_npy(bytes.data(), bytes.size(), "mem");
    EXPECT_EQ(p.data, a.data);
    std::remove(path.c_str());
  }
  EXPECT_EQ(NpyArray::b1({0, 3, 1}).data, (std::vector<char>{0, 1, 1}));
}

TEST(Npy, UnicodeHelper) {
  const NpyArray a = NpyArray::unicode("h\xc3\xa9!");
  EXPECT_EQ(a.dtype, "<U3");
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{1}));
  EXPECT_EQ(a.data, (std::vector<char>{'h', 0, 0, 0, char(0xe9), 0, 0, 0, '!', 0, 0, 0}));
  EXPECT_EQ(a.unicode_value(), "h\xc3\xa9!");
  EXPECT_EQ(NpyArray::unicode("").dtype, "<U1");
  EXPECT_EQ(NpyArray::unicode("").unicode_value(), "");
  EXPECT_EQ(NpyArray::f8({1.0}).unicode_value(), "");
}

// Code units that are no Unicode scalar value (a file may hold any 32-bit value) read as U+FFFD,
// so that the string is valid UTF-8 in a result JSON (found by fuzz_npy).
TEST(Npy, UnicodeValueIsValidUtf8) {
  NpyArray a = NpyArray::unicode("abcd");
  auto set = [&](int k, std::uint32_t cp) {
    for (int b = 0; b < 4; ++b) a.data[4 * k + b] = char((cp >> (8 * b)) & 0xff);
  };
  set(0, 0xD800);      // a surrogate
  set(1, 0x110000);    // above U+10FFFF
  set(2, 0xFFFFFFFF);
  set(3, 0x10FFFF);    // the last scalar value: kept
  EXPECT_EQ(a.unicode_value(), "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD\xF4\x8F\xBF\xBF");
  EXPECT_NO_THROW((void)nlohmann::json(a.unicode_value()).dump());
}

TEST(Npy, PointsRoundTrip) {
  const std::vector<Vec3d> pts = {{0.1, 0.2, 0.3}, {-1e10, 0, 5e-324}};
  const std::string path = temp_path("points.npy");
  write_npy(path, NpyArray::f8_n3(pts));
  EXPECT_EQ(read_points_npy(path), pts);
  EXPECT_TRUE(leftover_temporaries(path).empty()) << "the temporary file was left behind";
  std::remove(path.c_str());
}

// Bytes in memory read as a file does, empty arrays included (an empty buffer's data() may be
// null: the in-memory source must not pass it to memcpy; the fuzzer's UBSan build found it).
TEST(Npy, ParsesFromMemoryLikeAFile) {
  for (const std::vector<Vec3d>& pts : {std::vector<Vec3d>{}, std::vector<Vec3d>{{0.1, 0.2, 0.3}, {-1e10, 0, 5e-324}}}) {
    const std::string bytes = npy_bytes(NpyArray::f8_n3(pts));
    EXPECT_EQ(parse_points_npy(bytes.data(), bytes.size(), "mem.npy"), pts);
    const NpyArray a = parse_npy(bytes.data(), bytes.size(), "mem.npy");
    EXPECT_EQ(a.shape, (std::vector<std::size_t>{pts.size(), 3}));
    EXPECT_EQ(a.data.size(), 24 * pts.size());
  }
}

// A deflated .npz entry's plain size is only claimed by the ZIP directory: read_npy_from must not
// allocate it before the bytes arrive. Here the header claims 1 TiB of data and the source ends
// after 1 MiB: an InputError, not std::bad_alloc (or the OOM killer).
TEST(Npy, AClaimedSizeIsNotAllocatedUpFront) {
  // What npy_header writes for a float64 array of 2^37 elements (which we cannot make to write it).
  std::string head = "\x93NUMPY\x01";
  head += '\0';
  head += "v";
  head += '\0';
  head += "{'descr': '<f8', 'fortran_order': False, 'shape': (137438953472,), }";
  head.resize(127, ' ');
  head += '\n';
  const std::uint64_t claimed = head.size() + (std::uint64_t(1) << 40);
  std::uint64_t at = 0;
  const NpyByteSource source = [&](void* out, std::size_t n) {
    if (at + n > head.size() + (1u << 20)) throw file_error("lying.npz (entry 'a.npy')", "the deflate stream ends early");
    for (std::size_t i = 0; i < n; ++i, ++at) static_cast<char*>(out)[i] = at < head.size() ? head[at] : '\0';
  };
  expect_input_error([&] { read_npy_from(source, claimed, "lying.npz (entry 'a.npy')", NpyOrder::c_only, NpySize::claimed); },
                     "lying.npz", "ends early");
}

TEST(Npy, NpzRoundTrip) {
  std::map<std::string, NpyArray> z;
  z["distance"] = NpyArray::f8({1.5, -2.0});
  z["closest"] = NpyArray::f8_n3({{1, 2, 3}, {4, 5, 6}});
  z["triangle"] = NpyArray::i8({3, -1});
  z["inside"] = NpyArray::b1({1, 0});
  z["definition"] = NpyArray::unicode("generalized winding number");
  z["empty"] = NpyArray::f8({});
  const std::string path = temp_path("rt.npz");
  write_npz(path, z);
  const auto r = read_npz(path);
  ASSERT_EQ(r.size(), z.size());
  for (const auto& kv : z) {
    SCOPED_TRACE(kv.first);
    ASSERT_TRUE(r.count(kv.first));
    EXPECT_EQ(r.at(kv.first).dtype, kv.second.dtype);
    EXPECT_EQ(r.at(kv.first).shape, kv.second.shape);
    EXPECT_EQ(r.at(kv.first).data, kv.second.data);
  }
  EXPECT_EQ(r.at("definition").unicode_value(), "generalized winding number");
  std::remove(path.c_str());
}

TEST(Npy, NpzWithMoreThan65535EntriesUsesZip64) {
  std::map<std::string, NpyArray> z;
  for (int i = 0; i < 70000; ++i) z["a" + std::to_string(i)] = NpyArray::i8({i});
  const std::string path = temp_path("many.npz");
  write_npz(path, z);
  const auto r = read_npz(path);
  ASSERT_EQ(r.size(), 70000u);
  EXPECT_EQ(values<std::int64_t>(r.at("a69999")), (std::vector<std::int64_t>{69999}));
  std::remove(path.c_str());
}

// ---- NumPy interop ----

TEST(NpyNumpy, ReadsNpyFiles) {
  const std::vector<Vec3d> pts = {{0, 1, 2}, {-1.5, 0.25, 1e-3}, {3, 4, 5}, {0.1, 0.2, 0.3}};
  EXPECT_EQ(read_points_npy(fixture("points.npy")), pts);
  EXPECT_EQ(read_points_npy(fixture("points_v2.npy")), pts);
  const NpyArray f4 = read_npy(fixture("points_f4.npy"));
  EXPECT_EQ(f4.dtype, "<f4");
  EXPECT_EQ(f4.shape, (std::vector<std::size_t>{4, 3}));
  EXPECT_EQ(values<float>(f4)[4], 0.25f);
  // Big-endian data is converted to the little-endian form we keep.
  const NpyArray be = read_npy(fixture("big_endian.npy"));
  EXPECT_EQ(be.dtype, "<f8");
  EXPECT_EQ(values<double>(be), (std::vector<double>{1.0, -2.0, 0.5}));
}

// A bare query-set .npy: float64 or float32, either byte order, C or Fortran order.
TEST(NpyNumpy, ReadsPointsInEveryForm) {
  const std::vector<Vec3d> pts = {{0, 1, 2}, {-1.5, 0.25, 1e-3}, {3, 4, 5}, {0.1, 0.2, 0.3}};
  // The float32 values, exactly as double. Through a volatile: GCC 12's SLP vectorizer at -O3
  // folds the pair double(float(x)), double(float(y)) to x, y.
  auto f4 = [](double v) {
    volatile float f = float(v);
    return double(f);
  };
  std::vector<Vec3d> widened;
  for (const Vec3d& p : pts) widened.push_back(Vec3d(f4(p.x), f4(p.y), f4(p.z)));
  ASSERT_NE(widened, pts);
  for (const char* name : {"points.npy", "points_v2.npy", "points_f8_be.npy", "points_fortran.npy"})
    EXPECT_EQ(read_points_npy(fixture(name)), pts) << name;
  for (const char* name : {"points_f4.npy", "points_f4_be.npy", "points_f4_fortran_be.npy"})
    EXPECT_EQ(read_points_npy(fixture(name)), widened) << name;
}

TEST(NpyNumpy, FortranOrderOnlyWhenAsked) {
  const NpyArray a = read_npy(fixture("points_fortran.npy"), NpyOrder::c_or_fortran);
  EXPECT_TRUE(a.fortran_order);
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{4, 3}));
  EXPECT_EQ(values<double>(a)[1], -1.5);  // column-major: the second value is point 1's x
  EXPECT_FALSE(read_npy(fixture("points.npy"), NpyOrder::c_or_fortran).fortran_order);
  EXPECT_THROW(npy_bytes(a), std::invalid_argument);  // we write C order only
}

TEST(NpyNumpy, OurNpyBytesEqualNumpys) {
  // np.save of the same (4, 3) float64 array: identical bytes, header included.
  const std::vector<Vec3d> pts = {{0, 1, 2}, {-1.5, 0.25, 1e-3}, {3, 4, 5}, {0.1, 0.2, 0.3}};
  EXPECT_EQ(npy_bytes(NpyArray::f8_n3(pts)), read_file_bytes(fixture("points.npy")));
}

TEST(NpyNumpy, ReadsSavez) { expect_fixture_arrays(read_npz(fixture("savez.npz"))); }
TEST(NpyNumpy, ReadsSavezCompressed) { expect_fixture_arrays(read_npz(fixture("savez_compressed.npz"))); }
TEST(NpyNumpy, ReadsEntriesWithDataDescriptors) { expect_fixture_arrays(read_npz(fixture("descriptors.npz"))); }

TEST(NpyNumpy, NumpyReadsOurNpz) {
  if (!have_numpy()) GTEST_SKIP() << "python3 with numpy not available";
  std::map<std::string, NpyArray> z;
  z["distance"] = NpyArray::f8({1.5, -2.0});
  z["closest"] = NpyArray::f8_n3({{1, 2, 3}, {4, 5, 6}});
  z["triangle"] = NpyArray::i8({3, -1});
  z["inside"] = NpyArray::b1({1, 0});
  z["definition"] = NpyArray::unicode("winding h\xc3\xa9");
  const std::string path = temp_path("interop.npz"), npy = temp_path("interop.npy");
  write_npz(path, z);
  write_npy(npy, NpyArray::f8_n3({{0.1, 0.2, 0.3}}));
  const std::string cmd =
      "python3 -c \"import numpy as np, zipfile; zipfile.ZipFile('" + path + "').testzip() is None or exit(3); "
      "z = np.load('" + path + "'); "
      "assert sorted(z.files) == ['closest', 'definition', 'distance', 'inside', 'triangle'], z.files; "
      "assert z['distance'].tolist() == [1.5, -2.0]; "
      "assert z['closest'].shape == (2, 3) and z['closest'][1, 2] == 6; "
      "assert z['triangle'].dtype == np.int64 and z['triangle'].tolist() == [3, -1]; "
      "assert z['inside'].dtype == bool and z['inside'].tolist() == [True, False]; "
      "assert z['definition'][0] == 'winding h\\u00e9', z['definition']; "
      "p = np.load('" + npy + "'); assert p.shape == (1, 3) and p[0, 0] == 0.1\"";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::remove(path.c_str());
  std::remove(npy.c_str());
}

// An entry larger than the reader's input buffer: inflated in many pieces, straight into the array.
TEST(NpyNumpy, ReadsALargeSavezCompressed) {
  if (!have_numpy()) GTEST_SKIP() << "python3 with numpy not available";
  const std::string path = temp_path("large.npz");
  const std::string cmd = "python3 -c \"import numpy as np; i = np.arange(600000, dtype=np.int64); "
                          "np.savez_compressed('" + path + "', a=(i * 2654435761 % 1000003).astype(np.float64), "
                          "b=np.ones(3))\"";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const auto z = read_npz(path);
  const std::vector<double> a = values<double>(z.at("a"));
  ASSERT_EQ(a.size(), 600000u);
  for (std::int64_t i = 0; i < 600000; ++i)
    ASSERT_EQ(a[std::size_t(i)], double(i * 2654435761 % 1000003)) << i;
  EXPECT_EQ(values<double>(z.at("b")), (std::vector<double>{1, 1, 1}));
  std::remove(path.c_str());
}

// ---- malformed ----

TEST(NpyRejects, PointsWithTheWrongDtypeOrShape) {
  expect_input_error([] { read_points_npy(fixture("points_i8.npy")); }, "points_i8.npy", "dtype <i8 and shape (4, 3)");
  expect_input_error([] { read_points_npy(fixture("points_n4.npy")); }, "points_n4.npy", "dtype <f8 and shape (2, 4)");
  expect_input_error([] { read_points_npy(fixture("points_3d.npy")); }, "points_3d.npy", "shape (4, 3, 1)");
  expect_input_error([] { read_points_npy(fixture("big_endian.npy")); }, "big_endian.npy", "shape (3,)");
}
TEST(NpyRejects, NanPoint) {
  expect_input_error([] { read_points_npy(fixture("points_nan.npy")); }, "points_nan.npy", "point 1 has a NaN coordinate");
}
TEST(NpyRejects, FortranOrder) {
  expect_input_error([] { read_npy(fixture("fortran.npy")); }, "fortran.npy", "fortran_order");
}
TEST(NpyRejects, ObjectDtype) {
  expect_input_error([] { read_npy(fixture("object.npy")); }, "object.npy", "unsupported dtype '|O'");
}
TEST(NpyRejects, TruncatedNpy) {
  expect_input_error([] { read_npy(fixture("bad_truncated.npy")); }, "bad_truncated.npy", "truncated");
}
TEST(NpyRejects, BadMagic) {
  expect_input_error([] { read_npy(fixture("bad_magic.npy")); }, "bad_magic.npy", "bad magic");
}
TEST(NpyRejects, MissingFile) {
  expect_input_error([] { read_npy(fixture("nope.npy")); }, "nope.npy", "not found");
  expect_input_error([] { read_npz(fixture("nope.npz")); }, "nope.npz", "not found");
}
TEST(NpyRejects, TruncatedNpz) {
  expect_input_error([] { read_npz(fixture("bad_truncated.npz")); }, "bad_truncated.npz", "truncated");
}
TEST(NpyRejects, CorruptNpz) {
  expect_input_error([] { read_npz(fixture("bad_crc.npz")); }, "bad_crc.npz", "CRC-32 mismatch");
}
// Deflated entries: what zlib reports, and sizes in the directory that the stream belies. Each
// message names the file and the entry.
TEST(NpzDeflate, ReadsAGoodEntry) {
  const auto z = read_npz(fixture("deflate_good.npz"));
  ASSERT_EQ(z.size(), 1u);
  EXPECT_EQ(values<double>(z.at("a"))[3], -1.5);
}
TEST(NpzDeflate, CorruptStream) {
  expect_input_error([] { read_npz(fixture("deflate_corrupt.npz")); }, "deflate_corrupt.npz (entry 'a.npy')",
                     "corrupt compressed data (zlib: invalid block type)");
}
TEST(NpzDeflate, TruncatedStream) {
  expect_input_error([] { read_npz(fixture("deflate_truncated.npz")); }, "deflate_truncated.npz (entry 'a.npy')",
                     "truncated compressed data");
}
TEST(NpzDeflate, StreamShorterThanTheDirectorySays) {
  expect_input_error([] { read_npz(fixture("deflate_short.npz")); }, "deflate_short.npz (entry 'a.npy')",
                     "inflates to 216 bytes, fewer than the 224 the directory says");
}
TEST(NpzDeflate, StreamLongerThanTheDirectorySays) {
  expect_input_error([] { read_npz(fixture("deflate_long.npz")); }, "deflate_long.npz (entry 'a.npy')",
                     "inflates to more than the 224 bytes the directory says");
}

TEST(NpyRejects, NpyGivenAsNpz) {
  expect_input_error([] { read_npz(fixture("points.npy")); }, "points.npy", "not an .npz");
}
TEST(NpyRejects, ParseNpyNamesTheSource) {
  const std::string bytes = read_file_bytes(fixture("points.npy"));
  expect_input_error([&] { parse_npy(bytes.data(), bytes.size() - 1, "the-name"); }, "the-name", "truncated");
  expect_input_error([&] { parse_npy(bytes.data(), 5, "the-name"); }, "the-name", "truncated");
}

// Every prefix and many corruptions of NumPy-made files are rejected cleanly, never a crash.
TEST(NpyRejects, EveryPrefixAndByteFlip) {
  for (const char* name : {"savez.npz", "savez_compressed.npz", "points.npy"}) {
    const std::string bytes = read_file_bytes(fixture(name));
    const bool npz = std::string(name).find(".npz") != std::string::npos;
    const std::string path = temp_path(npz ? "fuzz.npz" : "fuzz.npy");
    auto attempt = [&](const std::string& b) {
      std::ofstream(path, std::ios::binary).write(b.data(), std::streamsize(b.size()));
      try {
        if (npz) read_npz(path); else read_npy(path);
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      }
    };
    for (std::size_t n = 0; n < bytes.size(); n += 17) attempt(bytes.substr(0, n));
    for (std::size_t i = 0; i < bytes.size(); i += 13) {
      std::string b = bytes;
      b[i] = char(b[i] ^ 0x5a);
      attempt(b);
    }
    std::remove(path.c_str());
  }
}
