// cgal_aabb: CGAL 5.5's AABB_tree over the mesh's triangles, used the way an expert would.
//
//  - Geometry: the method keeps the mesh as float32 vertices + uint32 index triples (the
//    contract's method precision). The tree's primitives are `AABB_primitive` with *external*
//    property maps (Tag_true) and no cached datum (Tag_false): a primitive is just its triangle
//    index (4 bytes), and the maps build the `Triangle_3` / reference point on the fly from the
//    shared arrays. So the tree stores nodes + ids, not a copy of every triangle.
//  - distance(p): the library's closest-point traversal (`Projection_traits`, exactly what
//    `closest_point_and_primitive(p, hint)` runs), seeded by `best_hint(p)` (the KD-tree's nearest
//    reference point when `kd_tree=true`, else the first primitive) or, with `coherent=true`, by
//    the previous query's (closest point, triangle): a valid upper bound, so answers are identical.
//    We subclass the traits only to count the boxes tested. Sign: the inside test below.
//  - inside(p): ray parity on the *same* tree, with CGAL's own machinery behind
//    `Side_of_triangle_mesh` (`internal::Ray_3_Triangle_3_traversal_traits`: a vertical ray first,
//    then random rays while the answer is degenerate: a ray through an edge or a vertex, or in a
//    triangle's plane). We do not use `Side_of_triangle_mesh` itself: it needs a FaceGraph
//    (building a Surface_mesh would double the memory and a second tree) and its retry loop is
//    unbounded (`do ... while (indeterminate)`), which can spin forever on a point lying on an
//    edge. Ours retries at most kMaxRandomRays times, then counts the query as `undecided` and
//    answers the last parity. A point on a triangle is on the boundary: answered inside.
//    With `kernel=epick` the predicates are exact (a degenerate hit is always detected); with
//    `simple_cartesian` they are plain double and may miscount a hit grazing an edge: that is
//    the kernel trade-off the parameter exposes.
//  - Degenerate (zero-area) triangles stay in the tree, so distance() sees them (their closest
//    point is the segment or point they collapse to), but the ray test skips them: CGAL's
//    ray-triangle predicate has the precondition "triangle not degenerate" (an assertion in
//    debug builds), and a zero-area triangle cannot change a ray's parity anyway.
//  - Threads: CGAL 5.5 builds the AABB tree and its KD-tree sequentially: the registration says so
//    (no caps.parallel_build), and a result records build.threads 1. Queries run on the job's threads: both
//    trees are const once built (built here, never lazily by a query), traversals are const, and
//    each thread's query state keeps its own hint and counters (CgalQueries).
#include <CGAL/AABB_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/internal/Side_of_triangle_mesh/Point_inside_vertical_ray_cast.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/version.h>

#include <boost/iterator/counting_iterator.hpp>
#include <boost/property_map/property_map.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "harness/core/library_versions.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/method_support.hpp"
#include "harness/core/registry.hpp"
#include "harness/core/shared_structure_method.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/process_memory.hpp"

namespace bvhbench {
namespace {

/// The geometry the method keeps: #V float32 positions and #F vertex-index triples.
struct Geometry {
  std::vector<Vec3f> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

template <class K>
typename K::Point_3 to_point(const Vec3f& v) {
  return typename K::Point_3(double(v.x), double(v.y), double(v.z));
}

/// Triangles fetched by the tree on this thread (TriangleMap). The map is one object inside the
/// tree, shared by every thread's queries, so it counts into the calling thread's counter, and a
/// query state takes the difference across each query: its own count, whatever other threads do.
thread_local std::uint64_t t_triangles_fetched = 0;

/// What both property maps below are: a readable map from triangle index to a Value computed
/// from the shared geometry (the type names Boost's property_traits read).
template <class Value>
struct GeometryMap {
  using key_type = std::uint32_t;
  using value_type = Value;
  using reference = Value;
  using category = boost::readable_property_map_tag;
  const Geometry* g = nullptr;
};

/// Triangle index -> K::Triangle_3, built on the fly from the shared geometry. Each call is one
/// triangle the library is about to test, so the map also counts them (t_triangles_fetched).
template <class K>
struct TriangleMap : GeometryMap<typename K::Triangle_3> {
  using typename GeometryMap<typename K::Triangle_3>::value_type;
  using typename GeometryMap<typename K::Triangle_3>::key_type;
  friend value_type get(const TriangleMap& m, key_type i) {
    ++t_triangles_fetched;
    const auto& t = m.g->triangles[i];
    return value_type(to_point<K>(m.g->vertices[t[0]]), to_point<K>(m.g->vertices[t[1]]),
                      to_point<K>(m.g->vertices[t[2]]));
  }
};

/// Triangle index -> a point on it (its first vertex): what the KD-tree indexes for hints.
template <class K>
struct ReferencePointMap : GeometryMap<typename K::Point_3> {
  using typename GeometryMap<typename K::Point_3>::value_type;
  using typename GeometryMap<typename K::Point_3>::key_type;
  friend value_type get(const ReferencePointMap& m, key_type i) {
    return to_point<K>(m.g->vertices[m.g->triangles[i][0]]);
  }
};

/// CGAL's Side_of_triangle_mesh ray traversal, plus two things: degenerate triangles are
/// skipped (the predicate's precondition) and every box test is counted.
template <class Tree, class K, class VerticalTag>
class RayParityTraits
    : public CGAL::internal::Ray_3_Triangle_3_traversal_traits<
          typename Tree::AABB_traits, K, CGAL::internal::Default_tree_helper<Tree>, VerticalTag> {
  using Base = CGAL::internal::Ray_3_Triangle_3_traversal_traits<
      typename Tree::AABB_traits, K, CGAL::internal::Default_tree_helper<Tree>, VerticalTag>;
  using Primitive = typename Tree::Primitive;
  using Node = CGAL::AABB_node<typename Tree::AABB_traits>;

 public:
  RayParityTraits(std::pair<boost::logic::tribool, std::size_t>& status, const Tree& tree,
                  const std::vector<bool>& degenerate, std::uint64_t* nodes)
      : Base(status, tree.traits(), CGAL::internal::Default_tree_helper<Tree>()),
        degenerate_(degenerate),
        nodes_(nodes) {}

  template <class Query>
  void intersection(const Query& q, const Primitive& p) {
    if (!degenerate_[p.id()]) Base::intersection(q, p);
  }
  template <class Query>
  bool do_intersect(const Query& q, const Node& n) const {
    ++*nodes_;
    return Base::do_intersect(q, n);
  }

 private:
  const std::vector<bool>& degenerate_;
  std::uint64_t* nodes_;
};

/// The library's closest-point traversal, counting the boxes it tests.
template <class Traits>
class CountingProjectionTraits : public CGAL::internal::AABB_tree::Projection_traits<Traits> {
  using Base = CGAL::internal::AABB_tree::Projection_traits<Traits>;
  using Node = CGAL::AABB_node<Traits>;
  using Point = typename Traits::Point_3;

 public:
  CountingProjectionTraits(const Point& hint, std::uint32_t hint_id, const Traits& t,
                           std::uint64_t* nodes)
      : Base(hint, hint_id, t), nodes_(nodes) {}
  bool do_intersect(const Point& q, const Node& n) const {
    ++*nodes_;
    return Base::do_intersect(q, n);
  }

 private:
  std::uint64_t* nodes_;
};

struct Options {
  std::string kernel;     // build
  bool kd_tree = true;    // build
  bool coherent = false;  // query
};

/// The built structure, shared read-only by every thread's queries (CGAL's AABB_tree and its
/// KD-tree are const once built: both are built in build(), never lazily by a query).
template <class K>
struct CgalStructure {
  using Point = typename K::Point_3;
  using Primitive = CGAL::AABB_primitive<std::uint32_t, TriangleMap<K>, ReferencePointMap<K>,
                                         CGAL::Tag_true /*external maps*/, CGAL::Tag_false /*no cached datum*/>;
  using Traits = CGAL::AABB_traits<K, Primitive>;
  using Tree = CGAL::AABB_tree<Traits>;
  using Hint = typename Tree::Point_and_primitive_id;

  /// Random rays tried after the vertical one while the parity is undecided (a degenerate hit).
  static constexpr int kMaxRandomRays = 16;

  Options opt;
  Geometry geo;
  std::vector<bool> degenerate;
  std::size_t degenerate_count = 0;
  Tree tree;
  CGAL::Bbox_3 bbox;
  bool kd_built = false;
  std::size_t kd_bytes = 0;
  std::array<typename K::Vector_3, kMaxRandomRays> directions;
};

/// One thread's queries: the coherent hint and the counters.
template <class K>
class CgalQueries final : public QueryState {
  using S = CgalStructure<K>;
  using Point = typename S::Point;
  using Tree = typename S::Tree;
  using Traits = typename S::Traits;
  using Hint = typename S::Hint;

 public:
  explicit CgalQueries(const S& s) : s_(s) {}

  void reset_path() override { has_prev_ = false; }

  bool inside(const Vec3d& p) override {
    const std::uint64_t fetched0 = t_triangles_fetched;
    const bool r = inside_impl(Point(p.x, p.y, p.z));
    datum_fetches_ += t_triangles_fetched - fetched0;
    return r;
  }

  DistanceResult distance(const Vec3d& p) override {
    const std::uint64_t fetched0 = t_triangles_fetched;
    const Point q(p.x, p.y, p.z);
    const Hint hint = (s_.opt.coherent && has_prev_) ? prev_ : s_.tree.best_hint(q);
    CountingProjectionTraits<Traits> traits(hint.first, hint.second, s_.tree.traits(), &nodes_visited_);
    s_.tree.traversal(q, traits);
    const Hint best = traits.closest_point_and_primitive();
    if (s_.opt.coherent) {
      prev_ = best;
      has_prev_ = true;
    }

    DistanceResult r;
    r.closest = Vec3d(CGAL::to_double(best.first.x()), CGAL::to_double(best.first.y()),
                      CGAL::to_double(best.first.z()));
    r.triangle = std::int64_t(best.second);
    r.normal = face_normal(s_.geo.vertices, s_.geo.triangles[best.second]);
    const double d = norm(r.closest - p);
    // On the surface the sign is moot, and a ray from there is degenerate by construction.
    r.distance = (d > 0 && inside_impl(q)) ? -d : d;
    datum_fetches_ += t_triangles_fetched - fetched0;
    return r;
  }

  std::vector<Counter> counters() const override {
    return {{"triangles_tested", datum_fetches_},
            {"nodes_visited", nodes_visited_},
            {"rays_shot", rays_shot_},
            {"undecided", undecided_}};
  }
  void reset_counters() override { datum_fetches_ = nodes_visited_ = rays_shot_ = undecided_ = 0; }

 private:
  bool inside_impl(const Point& p) {
    const CGAL::Bbox_3& bbox = s_.bbox;
    // As Side_of_triangle_mesh: outside the box is outside (no ray needed).
    if (p.x() < bbox.xmin() || p.x() > bbox.xmax() || p.y() < bbox.ymin() ||
        p.y() > bbox.ymax() || p.z() < bbox.zmin() || p.z() > bbox.zmax())
      return false;

    // Vertical ray first, towards the nearer side of the box (fewer boxes crossed).
    const double dz = 2 * CGAL::to_double(p.z()) < bbox.zmin() + bbox.zmax() ? -1.0 : 1.0;
    std::pair<boost::logic::tribool, std::size_t> status(boost::logic::indeterminate, 0);
    {
      ++rays_shot_;
      typename K::Ray_3 ray(p, typename K::Vector_3(0, 0, dz));
      RayParityTraits<Tree, K, CGAL::Tag_true> traits(status, s_.tree, s_.degenerate, &nodes_visited_);
      s_.tree.traversal(ray, traits);
    }
    for (int i = 0; i < S::kMaxRandomRays && boost::logic::indeterminate(status.first); ++i) {
      ++rays_shot_;
      status = {boost::logic::indeterminate, 0};
      typename K::Ray_3 ray(p, s_.directions[std::size_t(i)]);
      RayParityTraits<Tree, K, CGAL::Tag_false> traits(status, s_.tree, s_.degenerate, &nodes_visited_);
      s_.tree.traversal(ray, traits);
    }
    if (boost::logic::indeterminate(status.first)) {
      ++undecided_;  // every ray grazed an edge: the point is (almost) on the surface
      return (status.second & 1) == 1;
    }
    if (!status.first) return true;  // the point lies on a triangle: boundary counts as inside
    return (status.second & 1) == 1;
  }

  const S& s_;
  bool has_prev_ = false;
  Hint prev_;
  std::uint64_t datum_fetches_ = 0, nodes_visited_ = 0, rays_shot_ = 0, undecided_ = 0;
};

template <class K>
class CgalAabb final : public SharedStructureMethod<CgalQueries<K>> {
  using S = CgalStructure<K>;
  using Point = typename S::Point;
  using Primitive = typename S::Primitive;
  using Traits = typename S::Traits;

 public:
  explicit CgalAabb(const Options& o) {
    s_.opt = o;
    // Fixed directions, so that counters are deterministic and independent of query order.
    std::mt19937_64 rng(1340818006);  // CGAL's own seed for Point_inside_vertical_ray_cast
    std::normal_distribution<double> n01;
    for (auto& d : s_.directions) {
      double x, y, z, l;
      do {
        x = n01(rng), y = n01(rng), z = n01(rng);
        l = std::sqrt(x * x + y * y + z * z);
      } while (l < 1e-3);
      d = typename K::Vector_3(x / l, y / l, z / l);
    }
  }

  /// The trees stay; the next queries hint as `params` say, from a fresh state.
  void set_query_options(const Params& params) override {
    s_.opt.coherent = params.get_bool("coherent");
    this->start_queries();
  }

  void build(const Mesh& mesh, const BuildContext& ctx) override {
    if (mesh.triangles.empty()) throw InputError("cgal_aabb: the mesh has no triangle");
    try {
      s_.geo.vertices = float32_vertices(mesh.vertices);
      s_.geo.triangles = mesh.triangles;
      s_.geo.triangles.shrink_to_fit();

      const std::size_t nt = s_.geo.triangles.size();
      s_.degenerate.assign(nt, false);
      typename K::Collinear_3 collinear = K().collinear_3_object();
      for (std::size_t i = 0; i < nt; ++i) {
        const auto& t = s_.geo.triangles[i];
        if (collinear(to_point<K>(s_.geo.vertices[t[0]]), to_point<K>(s_.geo.vertices[t[1]]),
                      to_point<K>(s_.geo.vertices[t[2]]))) {
          s_.degenerate[i] = true;
          ++s_.degenerate_count;
        }
      }

      TriangleMap<K> tmap;
      tmap.g = &s_.geo;
      ReferencePointMap<K> pmap;
      pmap.g = &s_.geo;
      s_.tree.insert(boost::counting_iterator<std::uint32_t>(0),
                     boost::counting_iterator<std::uint32_t>(std::uint32_t(nt)), tmap, pmap);
      s_.tree.build();
      s_.bbox = s_.tree.bbox();

      // The KD-tree only serves distance queries: build it now (not lazily on the first query,
      // which would hide its cost in the query timings), and only when distances will be asked.
      s_.kd_built = s_.opt.kd_tree && ctx.query_type == QueryType::distance;
      if (s_.kd_built) {
        const std::size_t rss0 = current_rss_bytes();
        s_.tree.accelerate_distance_queries();
        const std::size_t rss1 = current_rss_bytes();
        // The KD-tree (AABB_search_tree over a CGAL Kd_tree) keeps a copy of one decorated point
        // per primitive (Point_3 + id + flag, 32 bytes) and a pointer to it, plus its nodes. Its
        // node storage is private, so we measure the RSS growth around its construction and
        // keep the larger of that and the lower bound from the points alone.
        const std::size_t lower = nt * (sizeof(Point) + 8 + sizeof(void*));
        s_.kd_bytes = std::max(lower, rss1 > rss0 ? rss1 - rss0 : std::size_t(0));
      } else {
        s_.tree.do_not_accelerate_distance_queries();
      }
    } catch (const CGAL::Failure_exception& e) {
      throw std::runtime_error(std::string("cgal_aabb: CGAL failure during build: ") + e.what());
    }
    this->start_queries();
  }


  std::size_t structure_bytes() const override {
    return geometry_bytes() + tree_bytes() + s_.kd_bytes;
  }

  nlohmann::json info() const override {
    return {{"kernel", s_.opt.kernel},
            {"triangles", s_.geo.triangles.size()},
            {"degenerate_triangles", s_.degenerate_count},
            {"tree_nodes", s_.tree.size() > 1 ? s_.tree.size() - 1 : 0},
            {"node_bytes", sizeof(CGAL::AABB_node<Traits>)},
            {"primitive_bytes", sizeof(Primitive)},
            {"kd_tree_built", s_.kd_built},
            {"bytes", {{"geometry", geometry_bytes()}, {"aabb_tree", tree_bytes()}, {"kd_tree", s_.kd_bytes}}}};
  }

 private:
  std::unique_ptr<CgalQueries<K>> make_state() const override { return std::make_unique<CgalQueries<K>>(s_); }

  std::size_t geometry_bytes() const {
    return s_.geo.vertices.capacity() * sizeof(Vec3f) +
           s_.geo.triangles.capacity() * sizeof(s_.geo.triangles[0]) + (s_.degenerate.capacity() + 7) / 8;
  }
  /// Exact: the tree reserves #F-1 nodes and keeps one Primitive (its id) per triangle.
  std::size_t tree_bytes() const {
    const std::size_t n = s_.tree.size();
    return (n > 1 ? n - 1 : 0) * sizeof(CGAL::AABB_node<Traits>) + n * sizeof(Primitive);
  }

  S s_;
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_cgal_aabb(bvhbench::Registry& r) {
  using namespace bvhbench;
  note_library_version("cgal", CGAL_VERSION_STR);
  MethodInfo m = MethodInfo::named("cgal_aabb",
                                   "CGAL AABB_tree: closest_point_and_primitive distance (KD-tree or coherent hint); inside by "
                                   "Side_of_triangle_mesh's ray parity on the same tree");
  // Capabilities, said once here (false unless set).
  m.caps.inside = true; m.caps.distance = true; m.caps.closest_triangle = true; m.caps.coherence = true;
  m.caps.query_options_after_build = true;  // coherent is read by the queries alone
  m.caps.concurrent_queries = true;  // per-thread hint and counters over the const trees
  // None: CGAL is header-only and compiled here with our flags, with no run-time CPU dispatch;
  // the traversal and its filtered predicates run in plain double (interval filters under our
  // rounding mode) and fall back to GMP (Debian's is not a "fat" build, and an exact fallback
  // gives the same answer on any kernel). The counts depend on the input and the build alone.
  m.machine_dependent_counters = {};
  m.params = {
      {"kernel", ParamType::choice, ParamRole::build, "epick",
       "geometric kernel: epick (exact predicates) or simple_cartesian (Simple_cartesian<double>)",
       {"epick", "simple_cartesian"}},
      {"kd_tree", ParamType::boolean, ParamRole::build, "true",
       "accelerate_distance_queries: hint each distance query with the KD-tree's nearest vertex", {}},
      {"coherent", ParamType::boolean, ParamRole::query, "false",
       "hint each distance query with the previous closest point and triangle (haptic paths)", {}},
  };
  // Side_of_triangle_mesh counts a ray's crossings: parity, defined on closed input (its
  // documentation asks for closed meshes; overlapping shells still have one parity).
  m.inside = {{{}, {InsideRule::ray_parity, false, 0.5, InputContract::closed}, ""}};
  // Swept by `methods: all`: the defaults and the coherent variant (which only a path tells apart).
  m.sweep = {"", "coherent=true"};
  // The KD-tree is built for distance jobs only: with it, a structure serves one query type.
  m.sharing = [](const Params& p) {
    return p.get_bool("kd_tree") ? StructureSharing::same_query_type : StructureSharing::every_job;
  };
  m.create = [](const Params& p) -> std::unique_ptr<Method> {
    Options o;
    o.kernel = p.get("kernel");
    o.kd_tree = p.get_bool("kd_tree");
    o.coherent = p.get_bool("coherent");
    if (o.kernel == "simple_cartesian")
      return std::make_unique<CgalAabb<CGAL::Simple_cartesian<double>>>(o);
    return std::make_unique<CgalAabb<CGAL::Exact_predicates_inexact_constructions_kernel>>(o);
  };
  r.add(std::move(m));
}
