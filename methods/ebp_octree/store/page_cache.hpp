#pragma once
/// The page cache of the out-of-core EBP-Octree: decoded pages (reader.hpp) with their query
/// state, under a byte budget, a resident page drawn at random evicted first. The top tree, the
/// directory and the per-page bookkeeping (16 bytes a page) are pinned outside the budget. A page
/// larger than the whole budget is still loaded (everything else is evicted first), so any budget
/// works.
///
/// Why random, not least recently used: a haptic loop replays a path, and a path whose pages are a
/// little more than the budget is LRU's worst case, where every page is evicted just before it is
/// needed again. A random victim loses about the overflow's share of hits there, and where the
/// path fits it evicts nothing (figures: HISTORY.md, "The headline in instructions on every model,
/// and a random victim in the page cache"). The draws come from a fixed seed, so that for one query sequence
/// the hits, misses and evictions are the same on every run.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/store/reader.hpp"

namespace ebp {

class PageCache {
 public:
  /// How a full cache chooses the page it evicts, as a result records it (ooc_method.cpp).
  static constexpr const char* kEviction = "random resident page, fixed seed";
  struct Entry {
    std::unique_ptr<Page> page;
    std::optional<Query> query;  ///< over page->tree (which never moves)
    std::size_t bytes = 0;       ///< decoded page + query state
  };

  PageCache(const StoreReader& store, std::size_t budget_bytes, bool coherent);
  /// The page, loaded (and checked) on a miss. The reference stays valid until the next get().
  Entry& get(std::uint32_t id);
  /// Whether page `id` is loaded (a get() would not read it).
  bool resident(std::uint32_t id) const { return slot_[id] != nullptr; }
  /// Evicts everything (counters of the evicted queries are kept).
  void clear();
  std::size_t resident_bytes() const { return used_; }
  std::size_t resident_pages() const { return resident_.size(); }
  std::size_t budget() const { return budget_; }
  std::size_t bookkeeping_bytes() const;

  std::uint64_t hits = 0, misses = 0, bytes_read = 0, evictions = 0;
  /// Query counters of every page query, resident or evicted, since reset_counters().
  QueryCounters query_counters() const;
  void reset_counters();

 private:
  void evict(std::uint32_t id);
  /// A resident page drawn uniformly (resident_ must not be empty).
  std::uint32_t victim();
  const StoreReader& store_;
  std::size_t budget_;
  bool coherent_;
  std::vector<std::unique_ptr<Entry>> slot_;  // by page id
  std::vector<std::uint32_t> resident_;       // the resident pages' ids, in no order
  std::vector<std::uint32_t> position_;       // by page id: its index in resident_
  std::size_t used_ = 0;
  std::mt19937_64 draws_;  // the standard fixes its sequence; reduced by hand (victim())
  QueryCounters evicted_;
};

void add_counters(QueryCounters& a, const QueryCounters& b);

}  // namespace ebp
