// The in-memory EBP-Octree builder, build_octree (octree_build.hpp). Steps (DESIGN.md explains the why), each in its
// file of build/ shared with the external build (build_parts.hpp): frame.cpp, leaf_build.cpp,
// inner_build.cpp, colouring.cpp:
//   1. float geometry, bounding cube (enlarged, with exactly representable cell boundaries),
//      leaf level from the average edge length;
//   2. distribution: every triangle to every leaf cell it touches (bbox-restricted
//      rasterisation confirmed by the conservative separating-axis test), (morton, tri) pairs
//      sorted;
//   3. the node set: grey nodes (holding geometry) down to the leaf level, and the empty octants
//      of grey inner nodes as empty leaves (maximal empty cells: no merge step is needed);
//   4. leaves: triangle blocks, bounding planes (clustered face normals, offset to the support of
//      triangle ∩ cell), configuration (convex / concave / special), reference point;
//   5. inner nodes bottom-up: planes chosen among the children's, offset to the support of the
//      children's bounding volumes (vertices of cell box ∩ planes);
//   6. colouring: winding numbers of reference points and empty nodes by exact signed segment
//      crossings between adjacent cells, joined in a union-find with potentials, seeded by the
//      outside of the root (w = 0).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "methods/ebp_octree/build/octree_build.hpp"

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/parallel_for.hpp"
#include "methods/ebp_octree/core/face_sides.hpp"
#include "methods/ebp_octree/core/sub_references.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp {

using namespace detail;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Pair {
  std::uint64_t m;  // leaf Morton code
  std::uint32_t t;  // triangle
  bool operator<(const Pair& o) const { return m < o.m || (m == o.m && t < o.t); }
};

using Triangles = std::vector<std::array<std::uint32_t, 3>>;

void check_input(const std::vector<Vec3d>& vin, const Triangles& tin) {
  if (tin.empty()) throw std::invalid_argument("ebp_octree: the mesh has no triangle");
  if (tin.size() > kMaxTriangles)  // the LeafTri index shares its word with the flags
    throw std::invalid_argument("ebp_octree: " + std::to_string(tin.size()) + " triangles, more than the " +
                                std::to_string(kMaxTriangles) + " a tree can index");
  for (const Vec3d& v : vin)
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      throw std::invalid_argument("ebp_octree: non-finite vertex coordinate");
  for (const auto& t : tin)
    for (int k = 0; k < 3; ++k)
      if (t[k] >= vin.size()) throw std::invalid_argument("ebp_octree: vertex index out of range");
}

/// Step 1: the frame origin (into T), the vertices in float in the frame, and the frame: cube and
/// leaf level (T's root and stats).
Frame frame_the_geometry(const std::vector<Vec3d>& vin, const Triangles& tin, const BuildParams& prm, Octree& T,
                         std::vector<Vec3d>* V) {
  Box3d vertex_bounds;
  for (const Vec3d& v : vin) vertex_bounds.add(v);
  T.origin = choose_origin(vertex_bounds);
  V->resize(vin.size());
  for (std::size_t i = 0; i < vin.size(); ++i) (*V)[i] = round_to_float(vin[i] - T.origin);
  FrameAccumulator acc;
  for (const auto& t : tin) acc.add((*V)[t[0]], (*V)[t[1]], (*V)[t[2]]);
  const Frame F = compute_frame(acc, prm);
  T.root_lo = F.root_lo;
  T.root_centre = F.root_centre;
  T.root_size = F.root_size;
  T.leaf_level = F.leaf_level;
  Stats& S = T.stats;
  S.leaf_level = F.leaf_level;
  S.root_size = T.root_size;
  S.average_edge = F.average_edge;
  S.triangles = tin.size();
  return F;
}

/// Step 2: every triangle to every leaf cell it touches, as (Morton, triangle) pairs, sorted.
std::vector<Pair> distribute(const BuildContext& ctx, const std::vector<Vec3d>& V, const Triangles& tin, int threads) {
  const std::size_t nt = tin.size();
  std::vector<Pair> pairs;
  auto distribute_one = [&](std::size_t t, std::vector<Pair>& out, std::vector<std::uint64_t>& ms) {
    ms.clear();
    distribute_triangle(ctx, V[tin[t][0]], V[tin[t][1]], V[tin[t][2]], ms);
    for (std::uint64_t m : ms) out.push_back({m, std::uint32_t(t)});
  };
  if (threads <= 1) {
    pairs.reserve(nt * 2);
    std::vector<std::uint64_t> ms;
    for (std::size_t t = 0; t < nt; ++t) distribute_one(t, pairs, ms);
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  }
  tbb::enumerable_thread_specific<std::vector<Pair>> local;
  tbb::enumerable_thread_specific<std::vector<std::uint64_t>> local_ms;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      auto& out = local.local();
      auto& ms = local_ms.local();
      for (std::size_t t = r.begin(); t != r.end(); ++t) distribute_one(t, out, ms);
    });
    std::size_t total = 0;
    for (auto& v : local) total += v.size();
    pairs.reserve(total);
    for (auto& v : local) pairs.insert(pairs.end(), v.begin(), v.end());
    tbb::parallel_sort(pairs.begin(), pairs.end());
  });
  return pairs;
}

/// The leaves of the node set: one per distinct Morton code of the sorted pairs.
struct LeafRanges {
  std::vector<std::uint64_t> morton;  ///< per leaf, increasing
  std::vector<std::uint32_t> begin;   ///< per leaf, its first pair; one more entry: the pairs' end
  std::vector<std::uint32_t> node;    ///< per leaf, its node (set by make_nodes)
  std::size_t size() const { return morton.size(); }
};

LeafRanges leaf_ranges(const std::vector<Pair>& pairs) {
  LeafRanges R;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (i == 0 || pairs[i].m != pairs[i - 1].m) {
      R.morton.push_back(pairs[i].m);
      R.begin.push_back(std::uint32_t(i));
    }
  R.begin.push_back(std::uint32_t(pairs.size()));
  return R;
}

/// Per level, the Morton codes (increasing) of the grey cells: the leaves' and their ancestors'.
std::vector<std::vector<std::uint64_t>> grey_cells(const LeafRanges& leaves, int L) {
  std::vector<std::vector<std::uint64_t>> grey(L + 1);
  grey[L] = leaves.morton;
  for (int l = L - 1; l >= 0; --l)
    for (std::uint64_t mm : grey[l + 1]) {
      const std::uint64_t p = mm >> 3;
      if (grey[l].empty() || grey[l].back() != p) grey[l].push_back(p);
    }
  return grey;
}

/// The octcodes of every node, sorted (pre-order): the grey cells and the empty octants of grey
/// inner nodes (maximal empty cells: no merge step is needed).
std::vector<Octcode> node_codes(const std::vector<std::vector<std::uint64_t>>& grey, int L) {
  std::vector<Octcode> codes;
  for (int l = 0; l <= L; ++l)
    for (std::uint64_t g : grey[l]) codes.push_back(octcode_make(l, g));
  for (int l = 0; l < L; ++l)
    for (std::uint64_t g : grey[l])
      for (std::uint64_t o = 0; o < 8; ++o) {
        const std::uint64_t c = (g << 3) | o;
        if (!std::binary_search(grey[l + 1].begin(), grey[l + 1].end(), c)) codes.push_back(octcode_make(l + 1, c));
      }
  std::sort(codes.begin(), codes.end());
  if (codes.size() >= 0xffffffffull) throw std::runtime_error("ebp_octree: too many nodes");
  return codes;
}

/// Step 3: the node set in T (nodes, children, leaves sized), each leaf's node in leaves->node.
/// Returns the number of grey inner nodes.
std::size_t make_nodes(LeafRanges* leaves, int L, Octree& T) {
  const std::vector<std::vector<std::uint64_t>> grey = grey_cells(*leaves, L);
  const std::vector<Octcode> codes = node_codes(grey, L);
  const std::size_t N = codes.size();
  T.nodes.resize(N);
  auto index_of = [&](Octcode c) {
    return std::uint32_t(std::lower_bound(codes.begin(), codes.end(), c) - codes.begin());
  };
  std::size_t ninner = 0;
  for (int l = 0; l < L; ++l) ninner += grey[l].size();
  T.children.resize(ninner * 8);
  T.leaves.resize(leaves->size());
  leaves->node.assign(leaves->size(), 0);
  std::uint32_t next_child = 0, next_leaf = 0;
  for (std::size_t i = 0; i < N; ++i) {
    Node& nd = T.nodes[i];
    nd.code = codes[i];
    nd.plane_begin = 0;
    nd.plane_count = 0;
    nd.config = LeafConfig::special;
    nd.next = index_of(octcode_subtree_end(codes[i]));
    const int l = octcode_level(codes[i]);
    const std::uint64_t mm = octcode_morton(codes[i]);
    const bool is_grey = std::binary_search(grey[l].begin(), grey[l].end(), mm);
    if (!is_grey) {
      nd.kind = NodeKind::white;  // coloured in step 6
      nd.index = 0;
    } else if (l < L) {
      nd.kind = NodeKind::inner;
      nd.index = next_child;
      for (int o = 0; o < 8; ++o) T.children[next_child + o] = index_of(octcode_child(codes[i], o));
      next_child += 8;
    } else {
      nd.kind = NodeKind::leaf;
      nd.index = next_leaf;  // leaves are met in Morton order = leaves->morton's order
      leaves->node[next_leaf] = std::uint32_t(i);
      ++next_leaf;
    }
  }
  return ninner;
}

/// Step 4: every grey leaf (its triangle block, planes, configuration, reference point and
/// colouring half-edges), in parallel. Fills tmp (per node) and halves (per leaf).
void build_leaves(const BuildContext& ctx, const std::vector<Pair>& pairs, const LeafRanges& leaves,
                  const std::vector<Vec3d>& V, const Triangles& tin, int threads, Octree& T, std::vector<NodeTmp>& tmp,
                  std::vector<LeafHalves>& halves) {
  T.tris.resize(pairs.size());
  par_for(threads, leaves.size(), [&](std::size_t li) {
    const std::uint32_t ni = leaves.node[li];
    Node& nd = T.nodes[ni];
    Leaf& lf = T.leaves[li];
    const std::uint32_t b = leaves.begin[li], e = leaves.begin[li + 1];
    std::vector<std::uint32_t> tri(e - b);
    std::vector<float> xyz(9 * std::size_t(e - b));
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t t = pairs[k].t;
      tri[k - b] = t;
      for (int q = 0; q < 3; ++q)
        for (int ax = 0; ax < 3; ++ax) xyz[9 * std::size_t(k - b) + 3 * q + ax] = float(V[tin[t][q]][ax]);
    }
    const std::uint32_t next = nd.next, index = nd.index;
    build_leaf(ctx, nd.code, e - b, tri.data(), xyz.data(), &nd, &lf, &T.tris[b], &tmp[ni], &halves[li]);
    nd.next = next;
    nd.index = index;
    lf.tri_begin = b;
  });
}

/// Step 5: the grey inner nodes bottom-up, each level in parallel, from their children's tmp.
void build_inner_nodes(const BuildContext& ctx, int L, int threads, const Octree& T, std::vector<NodeTmp>& tmp) {
  std::vector<std::vector<std::uint32_t>> inner_at(L);
  for (std::size_t i = 0; i < T.nodes.size(); ++i)
    if (T.nodes[i].kind == NodeKind::inner) inner_at[octcode_level(T.nodes[i].code)].push_back(std::uint32_t(i));
  for (int l = L - 1; l >= 0; --l) {
    const auto& list = inner_at[l];
    par_for(threads, list.size(), [&](std::size_t q) {
      const std::uint32_t ni = list[q];
      const Node& nd = T.nodes[ni];
      NodeTmp* ch[8];
      for (int o = 0; o < 8; ++o) {
        const std::uint32_t ci = T.children[nd.index + o];
        const NodeKind k = T.nodes[ci].kind;
        ch[o] = (k == NodeKind::inner || k == NodeKind::leaf) ? &tmp[ci] : nullptr;
      }
      build_inner(ctx, nd.code, ch, &tmp[ni]);
    });
  }
}

/// The nodes' planes into T's plane pool, in node order, with their figures.
void pool_planes(const std::vector<NodeTmp>& tmp, Octree& T) {
  Stats& S = T.stats;
  for (std::size_t i = 0; i < T.nodes.size(); ++i) {
    Node& nd = T.nodes[i];
    nd.plane_begin = std::uint32_t(T.planes.size());
    nd.plane_count = std::uint16_t(tmp[i].planes.size());
    T.planes.insert(T.planes.end(), tmp[i].planes.begin(), tmp[i].planes.end());
    S.max_planes_per_node = std::max<std::size_t>(S.max_planes_per_node, tmp[i].planes.size());
    if (nd.kind == NodeKind::leaf) {
      S.leaf_planes += tmp[i].planes.size();
      S.leaf_volume += tmp[i].volume;
      S.leaf_box_volume += tmp[i].box_volume;
    } else if (nd.kind == NodeKind::inner) {
      S.inner_planes += tmp[i].planes.size();
      S.inner_volume += tmp[i].volume;
      S.inner_box_volume += tmp[i].box_volume;
    }
  }
}

/// The node skeleton the colouring reads, from T and the leaves' half-edges (moved out).
Skeleton skeleton_of(const Octree& T, int L, const LeafRanges& leaves, std::vector<LeafHalves>&& halves) {
  const std::size_t N = T.nodes.size(), nleaves = leaves.size();
  Skeleton sk;
  sk.leaf_level = L;
  sk.code.resize(N);
  sk.kind.resize(N);
  sk.index.resize(N);
  for (std::size_t i = 0; i < N; ++i) {
    sk.code[i] = T.nodes[i].code;
    sk.kind[i] = T.nodes[i].kind;
    sk.index[i] = T.nodes[i].index;
  }
  sk.children = T.children;
  sk.leaf_node = leaves.node;
  sk.leaf_ref.resize(nleaves);
  sk.leaf_ref_valid.resize(nleaves);
  for (std::size_t li = 0; li < nleaves; ++li) {
    for (int k = 0; k < 3; ++k) sk.leaf_ref[li][k] = T.leaves[li].ref[k];
    sk.leaf_ref_valid[li] = T.leaves[li].ref_valid;
  }
  sk.leaf_halves = std::move(halves);
  return sk;
}

/// Step 6: the colouring (black empty nodes, the reference points' winding numbers).
void colour_tree(const Frame& F, Skeleton& sk, const std::vector<Vec3d>& V, const Triangles& tin, Octree& T) {
  auto winding_at = [&](const std::vector<Vec3d>& pts) {
    std::vector<int> out;
    for (const Vec3d& p : pts) {
      double w = 0;
      for (const auto& t : tin) w += bvhbench::triangle_winding(p, V[t[0]], V[t[1]], V[t[2]]);
      out.push_back(int(std::lround(w)));
    }
    return out;
  };
  const Colouring C = colour(F, sk, winding_at);
  for (std::uint32_t i : C.black) T.nodes[i].kind = NodeKind::black;
  for (std::size_t li = 0; li < T.leaves.size(); ++li) T.leaves[li].ref_winding = C.ref_winding[li];
  Stats& S = T.stats;
  S.colour_fallbacks = C.colour_fallbacks;
  S.degenerate_edges = C.degenerate_edges;
  S.invalid_refs = C.invalid_refs;
}

/// The node counts by level, colour and leaf configuration.
void count_nodes(Octree& T, std::size_t ninner) {
  Stats& S = T.stats;
  S.nodes = T.nodes.size();
  S.leaves = T.leaves.size();
  S.inner = ninner;
  S.planes = T.planes.size();
  S.nodes_per_level.assign(T.leaf_level + 1, 0);
  for (const Node& nd : T.nodes) {
    S.nodes_per_level[octcode_level(nd.code)]++;
    if (nd.kind == NodeKind::white) ++S.white;
    if (nd.kind == NodeKind::black) ++S.black;
    if (nd.kind == NodeKind::leaf) {
      if (nd.config == LeafConfig::convex) ++S.convex;
      else if (nd.config == LeafConfig::concave) ++S.concave;
      else ++S.special;
    }
  }
  for (const Leaf& lf : T.leaves) S.max_refs_per_leaf = std::max<std::size_t>(S.max_refs_per_leaf, lf.tri_count);
}

/// Closedness by vertex index: every undirected edge is used as often in each direction. Then
/// the winding number is a function of the point, so a coherent query may count crossings from
/// the previous point instead of the leaf's reference (same integer, exactly).
bool is_closed(const Triangles& tin) {
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * tin.size());
  for (const auto& t : tin)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t u = t[k], v = t[(k + 1) % 3];
      if (u == v) continue;
      keys.push_back(u < v ? (u << 33 | v << 1 | 0u) : (v << 33 | u << 1 | 1u));
    }
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    long bal = 0;
    while (j < keys.size() && (keys[j] >> 1) == (keys[i] >> 1)) bal += (keys[j++] & 1u) ? -1 : 1;
    if (bal != 0) return false;
    i = j;
  }
  return true;
}

}  // namespace

Octree build_octree(const std::vector<Vec3d>& vin, const Triangles& tin, const BuildParams& prm,
                    const std::function<void(double)>& progress) {
  const auto t_start = Clock::now();
  auto report = [&](double f) { if (progress) progress(f); };
  check_input(vin, tin);
  const int threads = std::max(1, prm.threads);
  Octree T;
  T.num_triangles = std::uint32_t(tin.size());
  Stats& S = T.stats;

  std::vector<Vec3d> V;
  const Frame F = frame_the_geometry(vin, tin, prm, T, &V);
  const BuildContext ctx(F, prm);
  const int L = F.leaf_level;
  S.leaf_size = ctx.cs;
  report(0.02);

  auto t0 = Clock::now();
  const std::vector<Pair> pairs = distribute(ctx, V, tin, threads);
  S.seconds_distribute = since(t0);
  S.triangle_refs = pairs.size();
  report(0.25);

  LeafRanges leaves = leaf_ranges(pairs);
  const std::size_t ninner = make_nodes(&leaves, L, T);
  report(0.3);

  t0 = Clock::now();
  std::vector<NodeTmp> tmp(T.nodes.size());
  std::vector<LeafHalves> halves(leaves.size());
  build_leaves(ctx, pairs, leaves, V, tin, threads, T, tmp, halves);
  S.seconds_leaves = since(t0);
  report(0.6);

  t0 = Clock::now();
  build_inner_nodes(ctx, L, threads, T, tmp);
  pool_planes(tmp, T);
  std::vector<NodeTmp>().swap(tmp);
  S.seconds_inner = since(t0);
  report(0.8);

  t0 = Clock::now();
  Skeleton sk = skeleton_of(T, L, leaves, std::move(halves));
  colour_tree(F, sk, V, tin, T);
  S.seconds_colour = since(t0);

  count_nodes(T, ninner);
  if (vin.size() < (std::size_t(1) << 31)) T.closed = is_closed(tin);
  t0 = Clock::now();
  compute_leaf_blocks(T);  // derived boxes (leaf_blocks.hpp)
  compute_sub_references(T);  // derived reference points (sub_references.hpp)
  const auto t_sides = Clock::now();
  compute_face_sides(T, threads);  // the faces the distance's sign can be taken from (face_sides.hpp)
  S.seconds_face_sides = since(t_sides);
  S.seconds_derived = since(t0);
  S.build_seconds = since(t_start);
  report(1.0);
  return T;
}

}  // namespace ebp
