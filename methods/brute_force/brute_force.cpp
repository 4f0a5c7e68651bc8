// brute_force: the exact reference. Every query visits every triangle, in double precision.
//
//  - distance(p): min over triangles of the exact point-triangle distance (Ericson's closest
//    point, double); ties go to the lowest triangle index. The sign comes from inside(p).
//    The contact normal is the closest triangle's unit face normal (right-hand rule: outward on
//    an outward-oriented mesh).
//  - inside(p): generalized winding number w(p) = sum of signed solid angles / 4 pi
//    (Jacobson et al. 2013), inside iff w > winding_threshold (1/2). On a closed, consistently
//    oriented mesh that is the winding number's answer (up to rounding for points on the
//    surface), which ray parity shares unless shells overlap or the mesh is inside out; on open
//    ones a principled answer (its declaration, m.inside below, says so for the judging).
#include <cmath>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/core/shared_structure_method.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {
namespace {

/// The mesh, shared read-only by every thread's queries.
struct Geometry {
  double threshold;
  std::vector<Vec3d> v;
  std::vector<std::array<std::uint32_t, 3>> f;
};

/// One thread's queries: its triangles_tested counter. No path state.
class BruteForceQueries final : public QueryState {
 public:
  explicit BruteForceQueries(const Geometry& g) : g_(g) {}

  double winding(const Vec3d& p) {
    double w = 0;
    for (const auto& t : g_.f) w += triangle_winding(p, g_.v[t[0]], g_.v[t[1]], g_.v[t[2]]);
    triangles_tested_ += g_.f.size();
    return w;
  }

  bool inside(const Vec3d& p) override { return winding(p) > g_.threshold; }

  DistanceResult distance(const Vec3d& p) override {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_i = 0;
    Vec3d best_q;
    for (std::size_t i = 0; i < g_.f.size(); ++i) {
      const auto& t = g_.f[i];
      Vec3d q = closest_point_on_triangle(p, g_.v[t[0]], g_.v[t[1]], g_.v[t[2]]);
      double d2 = squared_norm(q - p);
      if (d2 < best) {
        best = d2;
        best_i = i;
        best_q = q;
      }
    }
    triangles_tested_ += g_.f.size();
    DistanceResult r;
    const auto& t = g_.f[best_i];
    r.closest = best_q;
    r.triangle = std::int64_t(best_i);
    r.normal = triangle_normal(g_.v[t[0]], g_.v[t[1]], g_.v[t[2]]);
    const double d = std::sqrt(best);
    r.distance = winding(p) > g_.threshold ? -d : d;
    return r;
  }

  std::vector<Counter> counters() const override { return {{"triangles_tested", triangles_tested_}}; }
  void reset_counters() override { triangles_tested_ = 0; }

 private:
  const Geometry& g_;
  std::uint64_t triangles_tested_ = 0;
};

class BruteForce final : public SharedStructureMethod<BruteForceQueries> {
 public:
  explicit BruteForce(const Params& p) { g_.threshold = p.get_real("winding_threshold"); }

  void build(const Mesh& mesh, const BuildContext&) override {
    // No triangle, no closest point: an answer would be made up (the mesh readers refuse such a
    // file first; this is for callers of the interface, as the other methods do).
    if (mesh.triangles.empty()) throw InputError("brute_force: the mesh has no triangle");
    g_.v = mesh.vertices;
    g_.f = mesh.triangles;
    start_queries();
  }


  std::size_t structure_bytes() const override {
    return g_.v.capacity() * sizeof(Vec3d) + g_.f.capacity() * sizeof(g_.f[0]);
  }

 private:
  std::unique_ptr<BruteForceQueries> make_state() const override { return std::make_unique<BruteForceQueries>(g_); }
  Geometry g_;
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_brute_force(bvhbench::Registry& r) {
  using namespace bvhbench;
  MethodInfo m = MethodInfo::named("brute_force",
                                   "Exact reference: every triangle per query, double precision; inside by the generalized winding number");
  // Capabilities, said once here (false unless set).
  m.caps.inside = true; m.caps.distance = true; m.caps.closest_triangle = true;
  m.caps.concurrent_queries = true;  // per-thread counters over the shared mesh
  m.machine_dependent_counters = {};  // none: our own loop over every triangle, no library
  m.params = {{"winding_threshold", ParamType::real, ParamRole::query, "0.5",
               "inside iff the generalized winding number exceeds this", {}, 0.0, 1.0}};
  // The generalized winding number, summed exactly over every triangle: defined on any soup.
  m.inside = {{{}, {InsideRule::generalized_winding_number, false, 0.5, InputContract::any}, "winding_threshold"}};
  m.create = [](const Params& p) { return std::make_unique<BruteForce>(p); };
  r.add(std::move(m));
}
