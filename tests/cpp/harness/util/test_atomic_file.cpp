// AtomicOutputFile (util/atomic_file.hpp): a file appears whole on commit() or not at all, its
// temporary is gone either way, and two writers of one path never share a temporary.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <stdexcept>
#include <string>

#include "harness/util/atomic_file.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

TEST(AtomicFile, CommitWritesTheFileAndLeavesNoTemporary) {
  TmpDir d;
  const std::string path = d.file("out.bin");
  {
    AtomicOutputFile f(path);
    EXPECT_EQ(leftover_temporaries(path).size(), 1u) << "the bytes go to a temporary first";
    EXPECT_FALSE(std::filesystem::exists(path)) << "nothing at PATH before commit()";
    f.write("abc");
    f.write(std::string("\0de", 3));
    EXPECT_EQ(f.offset(), 6u);
    f.commit();
  }
  EXPECT_EQ(read_file_bytes(path), std::string("abc\0de", 6));
  EXPECT_TRUE(leftover_temporaries(path).empty());
}

TEST(AtomicFile, WithoutCommitTheOldFileStaysAndTheTemporaryIsRemoved) {
  TmpDir d;
  const std::string path = d.file("out.json");
  write_file_bytes(path, "old");
  try {
    AtomicOutputFile f(path);
    f.write("new, half written");
    throw std::runtime_error("a failure on the way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read_file_bytes(path), "old");
  EXPECT_TRUE(leftover_temporaries(path).empty());
}

TEST(AtomicFile, AFailedCommitNamesTheFileAndLeavesNoTemporary) {
  TmpDir d;
  // The rename fails: PATH is a non-empty directory.
  const std::string path = d.file("taken");
  std::filesystem::create_directories(path + "/inside");
  AtomicOutputFile f(path);
  f.write("x");
  try {
    f.commit();
    ADD_FAILURE() << "commit() over a directory succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot write: "), std::string::npos) << e.what();
  }
  EXPECT_TRUE(leftover_temporaries(path).empty());
  EXPECT_TRUE(std::filesystem::is_directory(path + "/inside"));
}

TEST(AtomicFile, AnUnwritableFolderNamesTheFile) {
  TmpDir d;
  const std::string path = d.file("no_such_folder/out.json");
  try {
    AtomicOutputFile f(path);
    ADD_FAILURE() << "opened a file in a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot write: No such file or directory");
  }
}

// Two writers of one path at once (suites on several workers) each write their own temporary;
// the last commit wins with a whole file.
TEST(AtomicFile, TwoWritersOfOnePathDoNotShareATemporary) {
  TmpDir d;
  const std::string path = d.file("shared.json");
  AtomicOutputFile a(path), b(path);
  EXPECT_NE(a.temporary_path(), b.temporary_path());
  EXPECT_EQ(std::filesystem::path(a.temporary_path()).parent_path(), std::filesystem::path(path).parent_path());
  a.write("first writer");
  b.write("second");
  a.commit();
  EXPECT_EQ(read_file_bytes(path), "first writer");
  b.commit();
  EXPECT_EQ(read_file_bytes(path), "second");
  EXPECT_TRUE(leftover_temporaries(path).empty());
}

// The file gets the permissions a plain open() gives (0666 less the umask), not mkstemp's 0600.
TEST(AtomicFile, TheFileHasTheUsualPermissions) {
  TmpDir d;
  const std::string path = d.file("perm.txt");
  const mode_t mask = ::umask(022);
  AtomicOutputFile f(path);
  f.write("x");
  f.commit();
  ::umask(mask);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);
}
