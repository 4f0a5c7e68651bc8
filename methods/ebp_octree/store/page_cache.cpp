// The page cache: a dense list of the resident pages, O(1) per hit, per miss and per eviction.
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
    : store_(store), budget_(budget_bytes), coherent_(coherent), draws_(0x9e3779b97f4a7c15ull) {
  const std::size_t n = store.directory().size();
  slot_.resize(n);
  position_.assign(n, UINT32_MAX);
  resident_.reserve(n);
}

std::size_t PageCache::bookkeeping_bytes() const {
  return sizeof(*this) + slot_.capacity() * sizeof(slot_[0]) + (resident_.capacity() + position_.capacity()) * 4;
}

std::uint32_t PageCache::victim() {
  // Lemire's multiply-shift: uniform enough over a few thousand pages, and the same on every
  // standard library (std::uniform_int_distribution's algorithm is the library's choice).
  // 32 random bits times a count of pages (under 2^32) fits in 64 bits.
  const std::uint64_t r = (draws_() >> 32) * std::uint64_t(resident_.size());
  return resident_[std::size_t(r >> 32)];
}

void PageCache::evict(std::uint32_t id) {
  Entry& e = *slot_[id];
  if (e.query) add_counters(evicted_, e.query->counters);
  used_ -= e.bytes;
  ++evictions;
  const std::uint32_t last = resident_.back();
  resident_[position_[id]] = last;
  position_[last] = position_[id];
  resident_.pop_back();
  position_[id] = UINT32_MAX;
  slot_[id].reset();
}

PageCache::Entry& PageCache::get(std::uint32_t id) {
  if (Entry* e = slot_[id].get()) {
    ++hits;
    return *e;
  }
  ++misses;
  auto e = std::make_unique<Entry>();
  e->page = store_.load_page(id, &bytes_read);
  e->query.emplace(e->page->tree, coherent_);
  // The query's state: stamps, scratch, its path and room for its near sets (Query::state_bytes).
  e->bytes = e->page->bytes() + e->query->state_bytes() + sizeof(Entry);
  while (!resident_.empty() && used_ + e->bytes > budget_) evict(victim());
  used_ += e->bytes;
  position_[id] = std::uint32_t(resident_.size());
  resident_.push_back(id);
  slot_[id] = std::move(e);
  return *slot_[id];
}

void PageCache::clear() {
  while (!resident_.empty()) evict(resident_.back());
}

QueryCounters PageCache::query_counters() const {
  QueryCounters c = evicted_;
  for (std::uint32_t id : resident_) add_counters(c, slot_[id]->query->counters);
  return c;
}

void PageCache::reset_counters() {
  evicted_ = {};
  hits = misses = bytes_read = evictions = 0;
  for (std::uint32_t id : resident_) slot_[id]->query->counters = {};
}

}  // namespace ebp
