// ByteSource (the mesh reader's input): a file or bytes in memory, read in any order through
// seek(), hashed once and in order whatever the order of the reads.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "harness/util/byte_source.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/sha256.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;

namespace {

/// 20 MB of numbered lines: more than the 8 MiB read buffer.
std::string numbered_lines() {
  std::string s;
  for (int i = 1; s.size() < (std::size_t(20) << 20); ++i) s += "line " + std::to_string(i) + "\n";
  return s;
}

/// Reads lines from `src` until the one numbered `n`; its offset.
std::uint64_t offset_of_line(ByteSource& src, std::uint64_t n) {
  std::string_view ln;
  while (src.line_no() + 1 < n && src.line(ln)) {
  }
  return src.offset();
}

void check_reads_and_hash(ByteSource& src, const std::string& bytes) {
  // Forward to line 1000, back to the start, forward to the middle, then past what was read
  // (read through and hashed), back again, and the hash is the file's.
  const std::uint64_t at1000 = offset_of_line(src, 1000);
  std::string_view ln;
  ASSERT_TRUE(src.line(ln));
  EXPECT_EQ(ln, "line 1000");
  src.seek(0, 0);
  ASSERT_TRUE(src.line(ln));
  EXPECT_EQ(ln, "line 1");
  EXPECT_EQ(src.line_no(), 1u);
  src.seek(at1000, 999);
  ASSERT_TRUE(src.line(ln));
  EXPECT_EQ(ln, "line 1000");
  EXPECT_EQ(src.line_no(), 1000u);
  const std::uint64_t far = bytes.rfind("line 1500000\n");
  ASSERT_NE(far, std::string::npos);
  src.seek(far, 1499999);  // never read before: read through on the way
  EXPECT_EQ(src.offset(), far);
  ASSERT_TRUE(src.line(ln));
  EXPECT_EQ(ln, "line 1500000");
  src.seek(5, 0);
  ASSERT_TRUE(src.fill(4));
  EXPECT_EQ(std::string(src.p, 4), "1\nli");
  EXPECT_EQ(src.finish_hash(), sha256_hex(bytes.data(), bytes.size()));
  EXPECT_EQ(src.finish_hash(), sha256_hex(bytes.data(), bytes.size())) << "the same on every call";
  src.seek(at1000, 999);
  ASSERT_TRUE(src.line(ln)) << "readable after the hash";
  EXPECT_EQ(ln, "line 1000");
}

}  // namespace

TEST(ByteSource, FileReadInAnyOrderHashedOnce) {
  const std::string bytes = numbered_lines();
  const std::string path = testing::TempDir() + "bvhbench_byte_source.txt";
  test::write_file_bytes(path, bytes);
  ByteSource src(path, nullptr);
  EXPECT_EQ(src.size(), bytes.size());
  check_reads_and_hash(src, bytes);
  EXPECT_GT(src.buffer_bytes(), 0u);
  EXPECT_LT(src.buffer_bytes(), bytes.size()) << "read through a buffer, not whole";
  std::remove(path.c_str());
}

TEST(ByteSource, BytesInMemoryTheSame) {
  const std::string bytes = numbered_lines();
  ByteSource src(bytes, "memory");
  EXPECT_EQ(src.name(), "memory");
  check_reads_and_hash(src, bytes);
  EXPECT_EQ(src.buffer_bytes(), 0u) << "not copied";
}

TEST(ByteSource, MissingFileAndDirectory) {
  test::expect_input_error([] { ByteSource("/no/such/file.ply", nullptr); }, "/no/such/file.ply", "file not found");
  test::expect_input_error([] { ByteSource(testing::TempDir(), nullptr); }, testing::TempDir(), "is a directory");
}
