// AtomicOutputFile's members for files written out of order and durably (the `.ebp` stores):
// write_at, resize, commit_durable, and that a failure among them leaves nothing behind.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "harness/util/atomic_file.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;

namespace {
std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
}  // namespace

TEST(AtomicOutputFilePositioned, WriteAtMixesWithSequentialWritesAndLeavesOffsetAlone) {
  test::TmpDir dir("atomic_at");
  const std::string path = dir.file("out.bin");
  {
    AtomicOutputFile f(path);
    f.write("abcdef");        // still in the FILE*'s buffer: write_at must not overtake it
    f.write_at(2, "XY", 2);   // over written bytes
    f.write_at(10, "Z", 1);   // past the end: the gap reads as zeros
    EXPECT_EQ(f.offset(), 6u);
    f.commit();
  }
  EXPECT_EQ(slurp(path), std::string("abXYef\0\0\0\0Z", 11));
  EXPECT_EQ(bvhbench::test::leftover_temporaries(path), std::vector<std::string>{});
}

TEST(AtomicOutputFilePositioned, ResizeCutsAndExtends) {
  test::TmpDir dir("atomic_resize");
  const std::string cut = dir.file("cut.bin"), grown = dir.file("grown.bin");
  {
    AtomicOutputFile f(cut);
    f.write_at(0, "0123456789", 10);
    f.resize(4);
    f.commit();
  }
  EXPECT_EQ(slurp(cut), "0123");
  {
    AtomicOutputFile f(grown);
    f.write("ab");
    f.resize(5);
    f.commit();
  }
  EXPECT_EQ(slurp(grown), std::string("ab\0\0\0", 5));
}

TEST(AtomicOutputFilePositioned, CommitDurableRenamesWithTheBytes) {
  test::TmpDir dir("atomic_durable");
  const std::string path = dir.file("store.ebp");
  {
    std::ofstream old(path, std::ios::binary);
    old << "old contents";
  }
  {
    AtomicOutputFile f(path);
    f.write_at(4, "tail", 4);
    f.write_at(0, "head", 4);
    EXPECT_EQ(slurp(path), "old contents");  // the name keeps the old file until the commit
    f.commit_durable();
  }
  EXPECT_EQ(slurp(path), "headtail");
  EXPECT_EQ(bvhbench::test::leftover_temporaries(path), std::vector<std::string>{});
}

TEST(AtomicOutputFilePositioned, AFailedWriteAtThrowsNamingTheFileAndLeavesNothing) {
  test::TmpDir dir("atomic_fail");
  const std::string path = dir.file("out.bin");
  try {
    AtomicOutputFile f(path);
    f.write_at(0, "x", 1);
    f.write_at(std::uint64_t(1) << 63, "y", 1);  // past any file's largest offset
    FAIL() << "write_at past the largest offset did not throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot write: "), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_EQ(bvhbench::test::leftover_temporaries(path), std::vector<std::string>{});
}
