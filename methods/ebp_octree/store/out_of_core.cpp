// Out-of-core queries. Inside: the pinned top tree is descended with exactly the arithmetic of
// ebp::Query::locate; a white/black top node answers at once, a page root hands the point to the
// page's own ebp::Query (the page is an Octree in the global frame, so the same leaf is reached
// by the same computation). Distance: branch and bound over the top tree, pages visited nearest
// bound first and skipped when their bound exceeds the best distance so far; inside a page the
// page query's own branch and bound (Query::distance_bound), started with the global best. The result is
// the lexicographic minimum of (squared distance, input triangle index) over all triangles, as
// the in-memory answer is whatever its visiting order: the same answer, bit for bit.
#include "methods/ebp_octree/store/out_of_core.hpp"

#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/search_stack.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ebp {

OutOfCore::OutOfCore(const std::string& path, std::size_t cache_bytes, bool coherent, bool cold)
    : OutOfCore(std::make_shared<const StoreReader>(path), cache_bytes, coherent, cold) {}

OutOfCore::OutOfCore(std::shared_ptr<const StoreReader> store, std::size_t cache_bytes, bool coherent, bool cold)
    : store_(std::move(store)),
      cache_(*store_, cache_bytes, coherent),
      coherent_(coherent),
      cold_(cold),
      path_(std::make_unique<CertifiedPath>()) {
  const FileHeader& h = store_->header();
  closed_ = (h.flags & kStoreClosed) != 0;
  top_ = store_->top_nodes().data();
  top_children_ = store_->top_children().data();
  top_planes_ = store_->top_planes().data();
  origin_ = Vec3d(h.origin[0], h.origin[1], h.origin[2]);
  root_lo_ = Vec3d(h.root_lo[0], h.root_lo[1], h.root_lo[2]);
  root_size_ = h.root_size;
  root_centre_ = root_lo_ + Vec3d(0.5, 0.5, 0.5) * root_size_;  // as build_octree computes it
  leaf_level_ = int(h.leaf_level);
  page_stamp_.assign(store_->directory().size(), 0);
  if (cold_) store_->drop_os_cache();
}

OutOfCore::~OutOfCore() = default;

void OutOfCore::set_scan_kernel(ScanKernel k) { path_->cert.set_kernel(k); }

void OutOfCore::reset_path() {
  path_->reset();
  last_page_ = last_k_ = last_leaf_ = last_node_ = UINT32_MAX;
  if (cold_) {
    cache_.clear();
    store_->drop_os_cache();
  }
  // The page queries' own path state: they keep it only while resident, and a stale leaf or
  // triangle of a page is still a valid hint for that page (answers do not depend on it).
}

QueryCounters OutOfCore::counters() const {
  QueryCounters c = cache_.query_counters();
  add_counters(c, top_counters_);
  return c;
}

void OutOfCore::reset_counters() {
  cache_.reset_counters();
  top_counters_ = {};
}

std::size_t OutOfCore::bytes() const {
  return sizeof(*this) + store_->pinned_bytes() + cache_.bookkeeping_bytes() + page_stamp_.capacity() * 4 +
         cache_.resident_bytes();
}

bool OutOfCore::inside_frame(const Vec3d& p) {
  // Same arithmetic as Query::locate.
  const int L = leaf_level_;
  const double inv = double(std::uint64_t(1) << L) / root_size_;
  const double G = double(std::uint64_t(1) << L);
  const double rx = (p.x - root_lo_.x) * inv, ry = (p.y - root_lo_.y) * inv, rz = (p.z - root_lo_.z) * inv;
  if (!(rx >= 0 && ry >= 0 && rz >= 0 && rx <= G && ry <= G && rz <= G)) {
    ++top_counters_.hit_white;
    return false;
  }
  const std::uint32_t gmax = (1u << L) - 1;
  const std::uint32_t x = std::min(std::uint32_t(rx), gmax), y = std::min(std::uint32_t(ry), gmax),
                      z = std::min(std::uint32_t(rz), gmax);
  std::uint32_t i = 0;
  int level = 0;
  while (top_[i].kind == TopKind::inner) {
    const int shift = L - level - 1;
    const std::uint32_t o = ((x >> shift) & 1u) | (((y >> shift) & 1u) << 1) | (((z >> shift) & 1u) << 2);
    i = top_children_[top_[i].index + o];
    ++level;
    ++top_counters_.nodes_visited;
  }
  switch (top_[i].kind) {
    case TopKind::white: ++top_counters_.hit_white; return false;
    case TopKind::black: ++top_counters_.hit_black; return true;
    default: break;
  }
  return cache_.get(top_[i].index).query->inside(p);
}

std::uint32_t OutOfCore::page_on_path(const Vec3d& p) {
  Vec3d lo = root_lo_;
  double size = root_size_;
  if (!cell_contains(lo, size, p))
    return UINT32_MAX;
  std::uint32_t i = 0;
  while (top_[i].kind == TopKind::inner) {
    size *= 0.5;
    const int o = child_octant(p, lo, size);
    lo = child_corner(lo, size, o);
    i = top_children_[top_[i].index + std::uint32_t(o)];
    ++top_counters_.nodes_visited;
  }
  return top_[i].kind == TopKind::page ? top_[i].index : UINT32_MAX;
}

namespace {
struct TopItem {
  Vec3d lo;
  double bound;
  std::uint32_t node;
  int level;
};

/// A lower bound on the distance from p to the geometry under a top node: its cell's box and
/// its planes (the point in the root-centred float frame, `slack` for the float evaluation).
struct TopBound {
  Vec3d p;
  float fx, fy, fz;
  double slack;
  TopBound(const Vec3d& p_, const Vec3d& root_centre, double root_size) : p(p_) {
    const Vec3d pr = p - root_centre;
    fx = float(pr.x);
    fy = float(pr.y);
    fz = float(pr.z);
    slack = 1e-6 * (std::max({std::fabs(pr.x), std::fabs(pr.y), std::fabs(pr.z)}) + root_size);
  }
  /// The bound, or the cell box's alone when that already exceeds `cutoff`: the node is pruned
  /// either way, and its planes are not evaluated (`*planes_tested` counts those that are).
  double operator()(const TopNode& nd, const Plane* planes, const Vec3d& lo, double size, double cutoff,
                    std::uint64_t* planes_tested = nullptr) const {
    const double d2 = cell_d2(lo, size, p);
    const double b = d2 > 0 ? std::sqrt(d2) : 0.0;
    if (b > cutoff) return b;
    if (planes_tested) *planes_tested += nd.plane_count;
    float m = -std::numeric_limits<float>::infinity();
    const Plane* pl = planes + nd.plane_begin;
    for (std::uint32_t k = 0; k < nd.plane_count; ++k)
      m = std::max(m, pl[k].n[0] * fx + pl[k].n[1] * fy + pl[k].n[2] * fz - pl[k].d);
    return std::max(b, double(m) - slack);
  }
};

/// Pages asked of the OS at once before a search's first read (OutOfCore::prefetch_pages):
/// enough for a probe's ball at contact and on its approach, few enough that a far point's
/// large ball does not flood the disk with pages its shrinking bound will skip.
constexpr int kPrefetchPages = 32;
}  // namespace

/// The best triangle so far of one distance query, over all pages.
struct OutOfCore::Best {
  DistanceBest b;  // key = input triangle index
  std::uint32_t page = UINT32_MAX, k = UINT32_MAX, leaf = UINT32_MAX, node = UINT32_MAX;
  float a[3], bb[3], c[3];
};

// Inside one page: the in-memory branch and bound (Query::distance_bound) of the page's own
// query, started with the global best (an upper bound that keeps its ties: pruning is by
// `bound > best` only) and with the input triangle index as the tie key, over the page's
// subtree (its roots' parent for a page below the top; the chain above it has no geometry).
void OutOfCore::page_distance(std::uint32_t id, PageCache::Entry& e, const Vec3d& p, Best& bst) {
  const Octree& t = e.page->tree;
  DistanceStart s;
  s.key_of = e.page->global_tri.data();
  s.node = e.page->chain == 0 ? 0u : e.page->chain - 2;  // chain - 1 is the white dummy
  bst.b.collect_page = id;
  if (seeded_ && last_page_ == id && last_k_ < t.tris.size()) {
    s.seed_tri = last_k_;
    s.seed_leaf = last_leaf_;
    s.seed_node = last_node_;
    // The page's near start (DESIGN.md, "Near start"): a page's geometry is all in its subtree
    // (the chain above it has none), and a near set is only gathered within the page's own
    // leaf cells (a stand-in for another page fails the gathering), so a search it answers is
    // the whole mesh's.
    s.near = true;
  }
  const Work w0 = work_of(e.query->counters);
  e.query->distance_bound(p, bst.b, s);
  page_work_ += work_of(e.query->counters) - w0;  // the page's share of the path's work
  if (!bst.b.collect && bst.b.k != UINT32_MAX) {
    const LeafTri& tr = t.tris[bst.b.k];
    bst.page = id;
    bst.k = bst.b.k;
    bst.leaf = bst.b.leaf;
    bst.node = bst.b.node;
    for (int i = 0; i < 3; ++i) { bst.a[i] = tr.a[i]; bst.bb[i] = tr.b[i]; bst.c[i] = tr.c[i]; }
  }
}

DistanceAnswer OutOfCore::unsigned_distance(const Vec3d& p) {
  DistanceAnswer r = unsigned_distance_frame(p - origin_);
  r.closest = r.closest + origin_;
  return r;
}

void OutOfCore::prefetch_pages(const Vec3d& p, double best, std::uint64_t qid) {
  const TopBound bound(p, root_centre_, root_size_);
  TopItem stack[8 * (kMaxLevel + 2)];
  int sp = 0, asked = 0;
  stack[sp++] = {root_lo_, 0.0, 0u, 0};
  while (sp > 0 && asked < kPrefetchPages) {
    const TopItem it = stack[--sp];
    const TopNode& nd = top_[it.node];
    if (nd.kind == TopKind::page) {
      if (page_stamp_[nd.index] != qid && !cache_.resident(nd.index)) {
        store_->will_need(nd.index);
        ++asked;
      }
      continue;
    }
    if (nd.kind != TopKind::inner) continue;
    const double csz = root_size_ / double(std::uint64_t(1) << (it.level + 1));
    TopItem kids[8];
    int nk = 0;
    for (int o = 0; o < 8; ++o) {
      const std::uint32_t ci = top_children_[nd.index + std::uint32_t(o)];
      const TopNode& cn = top_[ci];
      if (cn.kind != TopKind::inner && cn.kind != TopKind::page) continue;
      const Vec3d lo = child_corner(it.lo, csz, o);
      const double b = bound(cn, top_planes_, lo, csz, best);
      if (b > best) continue;
      kids[nk++] = {lo, b, ci, it.level + 1};
    }
    push_nearest_first(kids, nk, stack, sp);
  }
}

std::uint32_t OutOfCore::narrowed_start(const Vec3d& p, double best, Vec3d* start_lo, int* start_level) {
  const double r = best + search_tol(p, root_lo_, root_size_);
  std::uint32_t start = 0;
  while (top_[start].kind == TopKind::inner) {
    const double csz = root_size_ / double(std::uint64_t(1) << (*start_level + 1));
    const int o = child_octant(p, *start_lo, csz);
    const Vec3d clo = child_corner(*start_lo, csz, o);
    const std::uint32_t ci = top_children_[top_[start].index + std::uint32_t(o)];
    if (!cell_holds_ball(clo, csz, p, r) || (top_[ci].kind != TopKind::inner && top_[ci].kind != TopKind::page)) break;
    ++top_counters_.nodes_visited;
    start = ci;
    *start_lo = clo;
    ++*start_level;
  }
  return start;
}

void OutOfCore::search(const Vec3d& p, Best& bst) {
  const std::uint64_t qid = ++query_id_;
  bool prefetched = false;
  auto visit_page = [&](std::uint32_t id) {
    if (page_stamp_[id] == qid) return;
    page_stamp_[id] = qid;
    // The first page this search must read from the file: the others it may read are asked for
    // now, while this one is read (with no bound yet, after it: its answer gives the bound).
    if (!prefetched && !cache_.resident(id) && bst.b.best < std::numeric_limits<double>::infinity()) {
      prefetched = true;
      prefetch_pages(p, bst.b.best, qid);
    }
    page_distance(id, cache_.get(id), p, bst);
  };
  seeded_ = coherent_ && last_page_ != UINT32_MAX && seed_pays_at(p);
  if (seeded_) {
    visit_page(last_page_);
    if (bst.b.near_certified) return;  // the previous page's near set holds the ball: no other page can win
  }
  // The located start (as the in-memory search's): with no bound yet, the page on p's own path
  // first, whose own search starts from p's leaf, so that the top tree is descended with a tight
  // bound instead of weighing every child against an infinite one.
  if (!(bst.b.best < std::numeric_limits<double>::infinity())) {
    const std::uint32_t page = page_on_path(p);
    if (page != UINT32_MAX) visit_page(page);
  }

  const TopBound bound(p, root_centre_, root_size_);
  auto lower_bound = [&](const TopNode& nd, const Vec3d& lo, double size) {
    return bound(nd, top_planes_, lo, size, bst.b.best, &top_counters_.planes_tested);
  };

  Vec3d start_lo = root_lo_;
  int start_level = 0;
  const std::uint32_t start = bst.b.best < std::numeric_limits<double>::infinity()
                                  ? narrowed_start(p, bst.b.best, &start_lo, &start_level)
                                  : 0;
  TopItem stack[8 * (kMaxLevel + 2)];
  int sp = 0;
  stack[sp++] = {start_lo, lower_bound(top_[start], start_lo, root_size_ / double(std::uint64_t(1) << start_level)),
                 start, start_level};
  while (sp > 0) {
    const TopItem it = stack[--sp];
    if (it.bound > bst.b.best) continue;
    const TopNode& nd = top_[it.node];
    ++top_counters_.nodes_visited;
    if (nd.kind == TopKind::page) {
      visit_page(nd.index);
      continue;
    }
    if (nd.kind != TopKind::inner) continue;
    const int cl = it.level + 1;
    const double csz = root_size_ / double(std::uint64_t(1) << cl);
    TopItem kids[8];
    int nk = 0;
    for (int o = 0; o < 8; ++o) {
      const std::uint32_t ci = top_children_[nd.index + std::uint32_t(o)];
      const TopNode& cn = top_[ci];
      if (cn.kind == TopKind::white || cn.kind == TopKind::black) continue;
      const Vec3d lo = child_corner(it.lo, csz, o);
      const double b = lower_bound(cn, lo, csz);
      if (b > bst.b.best) continue;
      kids[nk++] = {lo, b, ci, cl};
    }
    push_nearest_first(kids, nk, stack, sp);
  }
}

double OutOfCore::leaf_cell() const { return root_size_ / double(std::uint64_t(1) << leaf_level_); }

bool OutOfCore::seed_pays_at(const Vec3d& p) const {
  return !is_jump(step_length(p, last_p_), last_d_, leaf_cell());
}

DistanceAnswer OutOfCore::unsigned_distance_frame(const Vec3d& p) {
  return coherent_ && certificate_ ? certified_distance(p) : searched_distance(p);
}

DistanceAnswer OutOfCore::searched_distance(const Vec3d& p) {
  Best bst;
  search(p, bst);
  DistanceAnswer ans;
  if (bst.page == UINT32_MAX) return ans;  // cannot happen: the mesh has a triangle
  ans.distance = bst.b.best;
  ans.closest = bst.b.closest;
  ans.normal = bvhbench::triangle_normal(to_d(bst.a), to_d(bst.bb), to_d(bst.c));
  ans.triangle = std::int64_t(bst.b.key);
  if (coherent_) {
    last_page_ = bst.page;
    last_k_ = bst.k;
    last_leaf_ = bst.leaf;
    last_node_ = bst.node;
    last_p_ = p;
    last_d_ = ans.distance;
  }
  return ans;
}

void OutOfCore::set_adaptive_certificate(bool on) { path_->set_adaptive(on); }

// As Query::certified_distance, over the pages: the renewal's collection crosses pages (the
// prune radius is the running best that the top tree and each page's branch and bound compare
// with, and each page offers its triangles with its id).
DistanceAnswer OutOfCore::certified_distance(const Vec3d& p) {
  TriangleSite site;
  const DistanceAnswer r = certified_query(
      *path_, p, leaf_cell(), root_lo_, root_size_, top_counters_, &site,
      [&] { return work_of(top_counters_) + page_work_; },
      [&](DistanceCertificate& cert, const Vec3d& centre) {
        Best bst;
        bst.b.collect = &cert;
        search(centre, bst);
      },
      [&] { return searched_distance(p); });
  if (site.page != UINT32_MAX) {
    last_page_ = site.page;
    last_k_ = site.k;
    last_leaf_ = site.leaf;
    last_node_ = site.node;
    last_p_ = p;
    last_d_ = r.distance;
  }
  return r;
}

DistanceAnswer OutOfCore::distance(const Vec3d& p) {
  // In the tree's frame (FileHeader::origin), translated once in double; the closest point back.
  const Vec3d q = p - origin_;
  DistanceAnswer r = unsigned_distance_frame(q);
  bool in;
  if (coherent_ && chained_sign_ && closed_) {  // the chained sign, as Query::distance
    if (path_->sign_chained(q, r.distance, certificate_tol(q, root_lo_, root_size_), &in))
      ++top_counters_.signs_chained;
    else
      in = inside_frame(q);
    path_->answered(q, r.distance, in);
  } else {
    in = inside_frame(q);
  }
  if (in) r.distance = -r.distance;
  r.closest = r.closest + origin_;
  return r;
}

}  // namespace ebp
