// brute_force: the exact reference. Every query visits every triangle, in double precision.
//
//  - distance(p): min over triangles of the exact point-triangle distance (Ericson's closest
//    point, double); ties go to the lowest triangle index. The sign comes from inside(p).
//    The contact normal is the closest triangle's unit face normal (right-hand rule: outward on
//    an outward-oriented mesh).
//  - inside(p): generalized winding number w(p) = sum of signed solid angles / 4 pi
//    (Jacobson et al. 2013), inside iff w > 1/2. Exactly the parity answer on closed meshes
//    (up to rounding for points on the surface), and a principled answer on open ones.
#include <cmath>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {
namespace {

class BruteForce final : public Method {
 public:
  explicit BruteForce(const Params& p) : threshold_(p.get_real("winding_threshold")) {}

  void build(const Mesh& mesh, const BuildContext&) override {
    // No triangle, no closest point: an answer would be made up (the mesh readers refuse such a
    // file first; this is for callers of the interface, as the other methods do).
    if (mesh.triangles.empty()) throw InputError("brute_force: the mesh has no triangle");
    v_ = mesh.vertices;
    f_ = mesh.triangles;
  }

  bool supports(QueryType) const override { return true; }

  double winding(const Vec3d& p) {
    double w = 0;
    for (const auto& t : f_) w += triangle_winding(p, v_[t[0]], v_[t[1]], v_[t[2]]);
    triangles_tested_ += f_.size();
    return w;
  }

  bool inside(const Vec3d& p) override { return winding(p) > threshold_; }

  DistanceResult distance(const Vec3d& p) override {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_i = 0;
    Vec3d best_q;
    for (std::size_t i = 0; i < f_.size(); ++i) {
      const auto& t = f_[i];
      Vec3d q = closest_point_on_triangle(p, v_[t[0]], v_[t[1]], v_[t[2]]);
      double d2 = squared_norm(q - p);
      if (d2 < best) {
        best = d2;
        best_i = i;
        best_q = q;
      }
    }
    triangles_tested_ += f_.size();
    DistanceResult r;
    const auto& t = f_[best_i];
    r.closest = best_q;
    r.triangle = std::int64_t(best_i);
    r.normal = triangle_normal(v_[t[0]], v_[t[1]], v_[t[2]]);
    const double d = std::sqrt(best);
    r.distance = winding(p) > threshold_ ? -d : d;
    return r;
  }

  std::size_t structure_bytes() const override {
    return v_.capacity() * sizeof(Vec3d) + f_.capacity() * sizeof(f_[0]);
  }
  std::vector<Counter> counters() const override { return {{"triangles_tested", triangles_tested_}}; }
  void reset_counters() override { triangles_tested_ = 0; }

 private:
  double threshold_;
  std::vector<Vec3d> v_;
  std::vector<std::array<std::uint32_t, 3>> f_;
  std::uint64_t triangles_tested_ = 0;
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_brute_force(bvhbench::Registry& r) {
  using namespace bvhbench;
  MethodInfo m;
  m.name = "brute_force";
  m.description = "Exact reference: every triangle per query, double precision; inside by the generalized winding number";
  m.caps = {true, true, true, false, false};
  m.machine_dependent_counters = {};  // none: our own loop over every triangle, no library
  m.params = {{"winding_threshold", ParamType::real, "0.5",
               "inside iff the generalized winding number exceeds this", {}, 0.0, 1.0}};
  m.create = [](const Params& p) { return std::make_unique<BruteForce>(p); };
  r.add(std::move(m));
}
