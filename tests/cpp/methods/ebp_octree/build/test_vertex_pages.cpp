// The float vertices paged from a temporary file (build/vertex_pages.hpp): what is gathered is what
// was appended, in any order and through a cache far smaller than the file; the second writing
// (rewind) replaces the first; a count other than announced is refused; the file leaves nothing
// behind in its directory.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <vector>

#include "methods/ebp_octree/build/vertex_pages.hpp"
#include "support/test_support.hpp"

using ebp::VertexPages;
namespace fs = std::filesystem;

namespace {

std::vector<float> coordinates(std::size_t n, float shift) {
  std::vector<float> v(3 * n);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float(i) * 0.5f + shift;
  return v;
}

/// Appended in chunks of varying sizes (page boundaries fall inside chunks and between them).
void append_all(VertexPages& vp, const std::vector<float>& v) {
  std::mt19937 rng(3);
  std::size_t done = 0, n = v.size() / 3;
  while (done < n) {
    const std::size_t k = std::min<std::size_t>(n - done, 1 + rng() % 1500);
    vp.append(&v[3 * done], k);
    done += k;
  }
}

}  // namespace

TEST(EbpVertexPages, GatherReturnsWhatWasAppendedThroughASmallCache) {
  bvhbench::test::TmpDir d("ebp_vertex_pages");
  const std::size_t n = 10 * VertexPages::kPageVertices + 77;  // 11 pages, the last one partial
  const std::vector<float> v = coordinates(n, 1.0f);
  VertexPages vp(d.p.string(), n, 1);  // the smallest cache: two pages
  append_all(vp, v);
  vp.finish();
  EXPECT_TRUE(fs::is_empty(d.p)) << "the vertex file is unlinked at once";

  std::mt19937 rng(5);
  std::vector<std::uint32_t> idx;
  for (int i = 0; i < 20000; ++i) idx.push_back(std::uint32_t(rng() % n));
  for (std::uint32_t i = 0; i < 3000; ++i) idx.push_back(i);               // in order
  idx.push_back(std::uint32_t(n - 1));                                      // the last vertex
  std::vector<float> got(3 * idx.size());
  vp.gather(idx.data(), idx.size(), got.data());
  std::size_t wrong = 0;
  for (std::size_t k = 0; k < idx.size(); ++k)
    if (std::memcmp(&got[3 * k], &v[3 * std::size_t(idx[k])], 12) != 0) ++wrong;
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(vp.reads(), idx.size());
  EXPECT_GT(vp.misses(), 1000u) << "random reads over 11 pages through 2 slots miss";
  EXPECT_LT(vp.misses(), vp.reads());
  EXPECT_LT(vp.resident_bytes(), 3 * VertexPages::kPageVertices * 12 + 4096) << "two pages and the tables";
}

TEST(EbpVertexPages, RewindReplacesTheFirstWriting) {
  bvhbench::test::TmpDir d("ebp_vertex_pages");
  const std::size_t n = 3 * VertexPages::kPageVertices + 5;
  VertexPages vp(d.p.string(), n, 1 << 20);
  append_all(vp, coordinates(n, 1.0f));
  vp.rewind();
  const std::vector<float> second = coordinates(n, -7.0f);
  append_all(vp, second);
  vp.finish();
  std::vector<std::uint32_t> idx;
  for (std::uint32_t i = 0; i < n; ++i) idx.push_back(std::uint32_t(n - 1 - i));
  std::vector<float> got(3 * n);
  vp.gather(idx.data(), n, got.data());
  EXPECT_EQ(std::memcmp(got.data() + 3 * (n - 1), second.data(), 12), 0);
  EXPECT_EQ(std::memcmp(got.data(), second.data() + 3 * (n - 1), 12), 0);
  EXPECT_EQ(vp.misses(), 4u) << "4 pages, each read once into a cache that holds them all";
}

TEST(EbpVertexPages, ACountOtherThanAnnouncedIsRefused) {
  bvhbench::test::TmpDir d("ebp_vertex_pages");
  VertexPages vp(d.p.string(), 100, 1 << 20);
  append_all(vp, coordinates(99, 0.0f));
  EXPECT_THROW(vp.finish(), std::logic_error);
}

TEST(EbpVertexPages, AMissingDirectoryIsNamed) {
  try {
    VertexPages vp("/nonexistent/bvhbench-dir", 10, 1 << 20);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/bvhbench-dir"), std::string::npos) << e.what();
  }
}
