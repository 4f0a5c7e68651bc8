// The out-of-core page cache's byte budget (store/page_cache.hpp; OUT_OF_CORE.md, "The page
// cache"): what it counts for a page covers what the page and its query hold on the heap, after
// coherent distance and inside queries too (near sets, certificates), so that the budget holds.
// Measured with glibc's allocator statistics: the heap in use grows by no more than the cache
// counts, but for the allocator's own overhead. (A page's query used to hold a certificate's
// table it never used: the heap was 2.2x the count.)
#include <gtest/gtest.h>

#include <malloc.h>

#include <cstdint>
#include <string>
#include <vector>

#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"
#include "methods/ebp_octree/store/page_cache.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace ebp_test;

#if defined(__GLIBC__)
TEST(EbpPageCache, CountsWhatPagesAndTheirQueriesHold) {
  const Mesh m = torus(400, 200);  // 160,000 triangles: ~100 pages of 16 KiB
  const Octree t = build(m);
  bvhbench::test::TmpDir d("ebp_page_cache_test");
  StoreWriteOptions wo;
  wo.page_target = 16 * 1024;
  wo.info_json = "{}";
  const std::string path = (d.p / "torus.ebp").string();
  write_store_atomic(t, path, wo);
  const StoreReader store(path);
  ASSERT_GT(store.directory().size(), 50u);

  PageCache cache(store, std::size_t(1) << 34, true);  // holds every page: nothing is freed
  const std::size_t before = mallinfo2().uordblks;
  for (std::uint32_t id = 0; id < store.directory().size(); ++id) {
    PageCache::Entry& e = cache.get(id);
    // A coherent walk over the page's first triangles: distance searches with the near start
    // (its near sets), and inside queries (the coherent step's near set).
    const Octree& pt = e.page->tree;
    for (std::uint32_t k = 0; k < pt.tris.size() && k < 40; ++k) {
      const Vec3d p = to_d(pt.tris[k].a) + Vec3d(1e-4, 2e-4, -1e-4);
      DistanceBest b;
      DistanceStart s;
      s.near = true;
      e.query->distance_bound(p, b, s);
      e.query->inside(p);
    }
  }
  const std::size_t held = mallinfo2().uordblks - before;
  // The allocator's own overhead (a chunk header and rounding per allocation, ~10 a page) is
  // not the cache's to count: 2 % of slack for it.
  EXPECT_LE(double(held), 1.02 * double(cache.resident_bytes() + cache.bookkeeping_bytes()))
      << "heap " << held << " B, counted " << cache.resident_bytes() << " B over " << cache.resident_pages() << " pages";
  EXPECT_GT(held, cache.resident_bytes() / 2) << "the count is of the same size as the heap";
}
#endif
