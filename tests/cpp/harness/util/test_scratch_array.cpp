// Arrays in temporary files behind a page cache: what is read is what was written, in any order,
// through a cache far smaller than the array; nothing is left in the folder; a folder that cannot
// hold the file is named in the message.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>

#include "harness/util/errors.hpp"
#include "harness/util/scratch_array.hpp"

namespace bvhbench {
namespace {

using Rec = std::array<double, 3>;

Rec value_of(std::uint64_t i) { return {double(i), -0.5 * double(i), double(i * i % 977) + 0.25}; }

TEST(ScratchArray, ReadsBackWhatWasWrittenThroughASmallCache) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "scratch_array_reads";
  std::filesystem::create_directories(dir);
  const std::uint64_t n = 7 * ScratchFile::kPageRecords + 123;  // a short last page
  {
    ScratchArray<Rec> a(dir.string(), "records", 1);  // the smallest cache: two pages
    std::vector<Rec> chunk;
    for (std::uint64_t i = 0; i < n; ++i) {
      chunk.push_back(value_of(i));
      if (chunk.size() == 1000 || i + 1 == n) {  // chunks that straddle the pages
        a.append(chunk.data(), chunk.size());
        chunk.clear();
      }
    }
    a.finish();
    ASSERT_EQ(a.size(), n);
    EXPECT_TRUE(std::filesystem::is_empty(dir));  // unlinked as soon as made
    for (std::uint64_t i = 0; i < n; ++i) ASSERT_EQ(a[i], value_of(i)) << i;
    std::mt19937_64 rng(3);
    for (int k = 0; k < 20000; ++k) {
      const std::uint64_t i = rng() % n;
      ASSERT_EQ(a[i], value_of(i)) << i;
    }
    EXPECT_GT(a.file().misses(), 8u);  // pages did come and go
    EXPECT_LE(a.resident_bytes(), 2 * ScratchFile::kPageRecords * sizeof(Rec) + 1024);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(ScratchArray, ReadingBeforeFinishOrPastTheEndIsAProgrammingError) {
  ScratchArray<std::uint32_t> a(testing::TempDir(), "ids", 1 << 20);
  const std::uint32_t v[3] = {1, 2, 3};
  a.append(v, 3);
  EXPECT_THROW(a[0], std::logic_error);
  a.finish();
  EXPECT_EQ(a[2], 3u);
  EXPECT_THROW(a[3], std::logic_error);
  EXPECT_THROW(a.push_back(4), std::logic_error);
}

TEST(ScratchArray, AFolderThatCannotHoldItIsNamed) {
  const std::string dir = testing::TempDir() + "/no/such/folder";
  try {
    ScratchArray<std::uint32_t> a(dir, "triangle grid ids", 1 << 20);
    ADD_FAILURE() << "made a file in a folder that does not exist";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(dir), std::string::npos) << what;
    EXPECT_NE(what.find("triangle grid ids"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace bvhbench
