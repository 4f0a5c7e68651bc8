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

namespace {

/// A torus of 160,000 triangles stored in pages of 16 KiB (about a thousand of them); its path.
std::string write_torus_store(const bvhbench::test::TmpDir& d) {
  const Octree t = build(torus(400, 200));
  StoreWriteOptions wo;
  wo.page_target = 16 * 1024;
  wo.info_json = "{}";
  const std::string path = (d.p / "torus.ebp").string();
  write_store_atomic(t, path, wo);
  return path;
}

}  // namespace

#if defined(__GLIBC__)
TEST(EbpPageCache, CountsWhatPagesAndTheirQueriesHold) {
  bvhbench::test::TmpDir d("ebp_page_cache_test");
  const StoreReader store(write_torus_store(d));
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

namespace {

/// Every page of `store` in order, `passes` times, through `cache`.
void replay_every_page(PageCache& cache, const StoreReader& store, int passes) {
  for (int pass = 0; pass < passes; ++pass)
    for (std::uint32_t id = 0; id < store.directory().size(); ++id) cache.get(id);
}

}  // namespace

// A haptic loop replays its path. Where the path's pages are a little more than the budget, an
// eviction of the least recently used page would miss on every page of every pass (each is
// evicted just before it comes round again); the cache's random victim keeps most of the hits.
// And its draws come from a fixed seed: the same sequence of pages, the same counters.
TEST(EbpPageCache, ALoopALittleLargerThanTheBudgetKeepsMostOfItsHits) {
  bvhbench::test::TmpDir d("ebp_page_cache_loop");
  const StoreReader store(write_torus_store(d));
  const std::size_t pages = store.directory().size();
  ASSERT_GT(pages, 50u);

  PageCache all(store, std::size_t(1) << 34, false);
  replay_every_page(all, store, 1);
  const std::size_t loop_bytes = all.resident_bytes();

  const std::size_t budget = loop_bytes - loop_bytes / 20;  // 95 % of the loop
  PageCache cache(store, budget, false);
  replay_every_page(cache, store, 1);  // the first pass misses on every page
  ASSERT_EQ(cache.misses, pages);
  cache.reset_counters();
  const int passes = 8;
  replay_every_page(cache, store, passes);
  const double hit_rate = double(cache.hits) / double(passes * pages);
  EXPECT_GT(hit_rate, 0.75) << cache.hits << " hits, " << cache.misses << " misses over " << passes << " passes of "
                            << pages << " pages";
  EXPECT_LE(cache.resident_bytes(), budget);

  PageCache again(store, budget, false);
  replay_every_page(again, store, 1);
  again.reset_counters();
  replay_every_page(again, store, passes);
  EXPECT_EQ(again.hits, cache.hits);
  EXPECT_EQ(again.misses, cache.misses);
  EXPECT_EQ(again.evictions, cache.evictions);
}
