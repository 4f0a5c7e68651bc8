#pragma once
/// The out-of-core EBP-Octree: queries answered from a `.ebp` store through a page cache with a
/// byte budget; the top of the tree is pinned. Same answers as the in-memory ebp::Query, bit for
/// bit (see OUT_OF_CORE.md for why).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "methods/ebp_octree/store/page_cache.hpp"
#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"

namespace ebp {

class OutOfCore {
 public:
  /// Opens the store (throws bvhbench::InputError on a bad file). `cold`: evict the file from
  /// the OS page cache now and at every reset_path(), and start each path with an empty cache.
  OutOfCore(const std::string& path, std::size_t cache_bytes, bool coherent, bool cold);
  /// Over a store another OutOfCore opened: one per thread, each with its own page cache (and
  /// its pages' query states), sharing the pinned top tree and the file. StoreReader's reads are
  /// const and positioned (pread), so several threads may load pages at once.
  OutOfCore(std::shared_ptr<const StoreReader> store, std::size_t cache_bytes, bool coherent, bool cold);
  ~OutOfCore();
  /// Points and closest points in world coordinates (translated once, in double, by the store's
  /// frame origin; FileHeader::origin).
  bool inside(const Vec3d& p) { return inside_frame(p - origin_); }
  DistanceAnswer distance(const Vec3d& p);
  DistanceAnswer unsigned_distance(const Vec3d& p);
  void reset_path();
  /// As Query's: the certificate and the chained sign on the coherent path (on by default).
  void set_certificate(bool on) { certificate_ = on; }
  void set_chained_sign(bool on) { chained_sign_ = on; }
  void set_adaptive_certificate(bool on);  ///< as Query::set_adaptive_certificate
  void set_scan_kernel(ScanKernel k);

  QueryCounters counters() const;  ///< page queries + the top-tree traversal
  void reset_counters();
  const PageCache& cache() const { return cache_; }
  const StoreReader& store() const { return *store_; }
  const std::shared_ptr<const StoreReader>& shared_store() const { return store_; }
  /// Pinned bytes (top tree, directory, bookkeeping) + the cache's resident bytes.
  std::size_t bytes() const;

 private:
  std::shared_ptr<const StoreReader> store_;
  PageCache cache_;
  bool coherent_, cold_;
  const TopNode* top_;
  const std::uint32_t* top_children_;
  const Plane* top_planes_;
  Vec3d origin_, root_lo_, root_centre_;
  double root_size_;
  int leaf_level_;
  QueryCounters top_counters_;
  Work page_work_;  ///< the pages' queries' work, summed as it is done (the certificate's choice)
  std::vector<std::uint64_t> page_stamp_;
  std::uint64_t query_id_ = 0;
  // coherent: page, LeafTri index and leaf (in that page) of the previous closest triangle
  std::uint32_t last_page_ = UINT32_MAX, last_k_ = UINT32_MAX, last_leaf_ = UINT32_MAX, last_node_ = UINT32_MAX;
  Vec3d last_p_;        // the point it was closest to, at distance last_d_
  double last_d_ = 0;
  bool seeded_ = false;  // the current search starts from it (is_jump, query.hpp)
  bool seed_pays_at(const Vec3d& p) const;
  double leaf_cell() const;

  bool closed_;
  bool certificate_ = true, chained_sign_ = true;
  std::unique_ptr<CertifiedPath> path_;

  struct Best;
  // The queries in the tree's frame.
  bool inside_frame(const Vec3d& p);
  DistanceAnswer unsigned_distance_frame(const Vec3d& p);
  void page_distance(std::uint32_t id, PageCache::Entry& e, const Vec3d& p, Best& b);
  /// The branch and bound over the top tree and the pages, from the running best in `b`.
  void search(const Vec3d& p, Best& b);
  /// The narrowed start (as the in-memory search's): with a finite best (the previous page's
  /// search), the deepest top node on p's path whose cell holds the ball (p, best + tol) strictly
  /// inside: all geometry outside that cell is strictly farther than the best (a triangle
  /// crossing into the cell is listed in the cell's own leaves too), so nothing it could win is
  /// lost, and the top tree's upper levels are not walked on every query. Its corner and level
  /// in *start_lo and *start_level (the root's on entry).
  std::uint32_t narrowed_start(const Vec3d& p, double best, Vec3d* start_lo, int* start_level);
  /// Before the first page a search must read: the pages it could still visit (top-tree bound
  /// within `best`), up to kPrefetchPages nearest first, that are not resident, asked of the OS
  /// at once (StoreReader::will_need), so that their reads overlap instead of following one
  /// another. Counts no work: it changes when bytes arrive, not what is read or answered.
  void prefetch_pages(const Vec3d& p, double best, std::uint64_t qid);
  /// The page whose cell holds p, down p's octants of the top tree; UINT32_MAX where p's top
  /// cell is empty or p is outside the root.
  std::uint32_t page_on_path(const Vec3d& p);
  DistanceAnswer searched_distance(const Vec3d& p);
  DistanceAnswer certified_distance(const Vec3d& p);
};

}  // namespace ebp
