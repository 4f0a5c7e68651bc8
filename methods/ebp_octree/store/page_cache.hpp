#pragma once
/// The page cache of the out-of-core EBP-Octree: decoded pages (reader.hpp) with their query
/// state, under a byte budget, least recently used evicted first. The top tree, the directory
/// and the per-page bookkeeping (24 bytes a page) are pinned outside the budget. A page larger
/// than the whole budget is still loaded (everything else is evicted first), so any budget works.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/store/reader.hpp"

namespace ebp {

class PageCache {
 public:
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
  std::size_t resident_pages() const { return resident_; }
  std::size_t budget() const { return budget_; }
  std::size_t bookkeeping_bytes() const;

  std::uint64_t hits = 0, misses = 0, bytes_read = 0, evictions = 0;
  /// Query counters of every page query, resident or evicted, since reset_counters().
  QueryCounters query_counters() const;
  void reset_counters();

 private:
  void unlink(std::uint32_t id);
  void push_front(std::uint32_t id);
  void evict(std::uint32_t id);
  const StoreReader& store_;
  std::size_t budget_;
  bool coherent_;
  std::vector<std::unique_ptr<Entry>> slot_;  // by page id
  std::vector<std::uint32_t> prev_, next_;    // LRU list, most recent at head_
  std::uint32_t head_ = UINT32_MAX, tail_ = UINT32_MAX;
  std::size_t used_ = 0, resident_ = 0;
  QueryCounters evicted_;
};

void add_counters(QueryCounters& a, const QueryCounters& b);

}  // namespace ebp
