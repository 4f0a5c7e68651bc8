// The page cache: an LRU list threaded through per-page arrays, O(1) per hit.
#include "methods/ebp_octree/store/page_cache.hpp"

namespace ebp {

void add_counters(QueryCounters& a, const QueryCounters& b) {
  a.nodes_visited += b.nodes_visited;
  a.planes_tested += b.planes_tested;
  a.triangles_tested += b.triangles_tested;
  a.hit_white += b.hit_white;
  a.hit_black += b.hit_black;
  a.hit_convex += b.hit_convex;
  a.hit_concave += b.hit_concave;
  a.hit_special += b.hit_special;
  a.exact_fallbacks += b.exact_fallbacks;
  a.certificate_renewals += b.certificate_renewals;
  a.certificate_served += b.certificate_served;
  a.signs_chained += b.signs_chained;
  a.signs_from_face += b.signs_from_face;
  a.near_served += b.near_served;
  a.near_gathered += b.near_gathered;
  a.near_tested += b.near_tested;
}

PageCache::PageCache(const StoreReader& store, std::size_t budget_bytes, bool coherent)
    : store_(store), budget_(budget_bytes), coherent_(coherent) {
  const std::size_t n = store.directory().size();
  slot_.resize(n);
  prev_.assign(n, UINT32_MAX);
  next_.assign(n, UINT32_MAX);
}

std::size_t PageCache::bookkeeping_bytes() const {
  return sizeof(*this) + slot_.capacity() * sizeof(slot_[0]) + (prev_.capacity() + next_.capacity()) * 4;
}

void PageCache::unlink(std::uint32_t id) {
  const std::uint32_t p = prev_[id], n = next_[id];
  if (p != UINT32_MAX) next_[p] = n; else head_ = n;
  if (n != UINT32_MAX) prev_[n] = p; else tail_ = p;
  prev_[id] = next_[id] = UINT32_MAX;
}

void PageCache::push_front(std::uint32_t id) {
  prev_[id] = UINT32_MAX;
  next_[id] = head_;
  if (head_ != UINT32_MAX) prev_[head_] = id;
  head_ = id;
  if (tail_ == UINT32_MAX) tail_ = id;
}

void PageCache::evict(std::uint32_t id) {
  Entry& e = *slot_[id];
  if (e.query) add_counters(evicted_, e.query->counters);
  used_ -= e.bytes;
  --resident_;
  ++evictions;
  unlink(id);
  slot_[id].reset();
}

PageCache::Entry& PageCache::get(std::uint32_t id) {
  if (Entry* e = slot_[id].get()) {
    ++hits;
    if (head_ != id) {
      unlink(id);
      push_front(id);
    }
    return *e;
  }
  ++misses;
  auto e = std::make_unique<Entry>();
  e->page = store_.load_page(id, &bytes_read);
  e->query.emplace(e->page->tree, coherent_);
  // The query's state: stamps, scratch, its path and room for its near sets (Query::state_bytes).
  e->bytes = e->page->bytes() + e->query->state_bytes() + sizeof(Entry);
  while (tail_ != UINT32_MAX && used_ + e->bytes > budget_) evict(tail_);
  used_ += e->bytes;
  ++resident_;
  slot_[id] = std::move(e);
  push_front(id);
  return *slot_[id];
}

void PageCache::clear() {
  while (tail_ != UINT32_MAX) evict(tail_);
}

QueryCounters PageCache::query_counters() const {
  QueryCounters c = evicted_;
  for (std::uint32_t id = head_; id != UINT32_MAX; id = next_[id]) add_counters(c, slot_[id]->query->counters);
  return c;
}

void PageCache::reset_counters() {
  evicted_ = {};
  hits = misses = bytes_read = evictions = 0;
  for (std::uint32_t id = head_; id != UINT32_MAX; id = next_[id]) slot_[id]->query->counters = {};
}

}  // namespace ebp
