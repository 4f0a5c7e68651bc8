// openvdb: a sparse signed distance field built by OpenVDB's mesh-to-volume (OpenVDB 10).
//
//  - build: the triangles go to openvdb::tools::meshToVolume in index space (origin at the mesh
//    box centre, so far-from-origin models keep their float precision) and become a FloatGrid
//    level set: exact distances in a narrow band around the surface, clamped to +ex (outside) and
//    -in (inside) world units beyond it. For distance jobs the polygon-index Int32Grid (closest
//    triangle per voxel) is kept too; inside jobs keep only the distance grid.
//  - band=auto models no more than the scene needs:
//      * inside jobs: the narrow band ex_band/in_band only. Beyond the band the level set's
//        inactive tiles still carry the right sign (signed flood fill), so inside(p) is answered
//        everywhere from a thin shell.
//      * distance jobs: the band must reach every point the query set visits. We bound
//        max |sdf| over the query box without computing any distance field: every triangle
//        corner lies on the surface, so for a lattice point l, |sdf(l)| <= min over sampled
//        corners |l - v|; a query point is within half a lattice cell diagonal of a lattice
//        point. The interior part is also capped by half the smallest mesh-box extent (a point
//        inside the solid reaches the surface before the nearest box face).
//    band=fixed uses ex_band/in_band as given. Either way, points beyond the band read the clamped
//    value: that is error in the accuracy figures, and it is left there.
//  - queries (one cached ValueAccessor per grid and per query thread, OpenVdbQueries): the value by trilinear (order
//    1, value and analytic gradient from the same 8 voxels) or OpenVDB's triquadratic sampler
//    (order 2, gradient by central differences); inside(p) is sdf(p) < 0; the normal is the
//    normalised gradient at p (points outward: the field grows outward); the closest point is
//    `closest_steps` projections q <- q - sdf(q) grad/|grad| starting at p; the closest triangle
//    is the polygon index stored at the voxel nearest p (then nearest q), -1 when none.
//  - max_voxels: the stored voxel count is estimated before building (Steiner-like shell volume
//    bounded by the dense box). Over it, `fit=true` (default) coarsens the voxel by 10% steps
//    until the field fits (recorded in the result's structure block: voxel_requested,
//    voxel_size, voxel_coarsened_to_fit), so that random points far from a big model still get a
//    field within a memory budget, at the accuracy that budget buys; `fit=false` refuses with a
//    message instead. Never a dense grid by default.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include "harness/core/library_versions.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/core/shared_structure_method.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {
namespace {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::Int32Grid;

constexpr double kPi = 3.14159265358979323846;

/// Upper bound of max |sdf| over `box`: lattice of (n+1)^3 points, each bounded by its nearest
/// sampled surface point (a triangle corner), plus half a lattice cell diagonal.
double surface_distance_bound(const Mesh& mesh, const Box3d& box, int n = 16,
                              std::size_t max_samples = 8192) {
  std::vector<Vec3d> s;
  const std::size_t nt = mesh.num_triangles();
  const std::size_t stride = std::max<std::size_t>(1, nt / max_samples);
  s.reserve(nt / stride + 1);
  for (std::size_t t = 0; t < nt; t += stride) s.push_back(mesh.vertex(std::uint32_t(t), int(t % 3)));
  const Vec3d ext = box.extent();
  const Vec3d cell = ext / double(n);
  double worst = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        const Vec3d l = box.lo + Vec3d(cell.x * i, cell.y * j, cell.z * k);
        double best = std::numeric_limits<double>::infinity();
        for (const Vec3d& v : s) best = std::min(best, squared_norm(l - v));
        worst = std::max(worst, best);
      }
  return std::sqrt(worst) + 0.5 * norm(cell);
}

double surface_area(const Mesh& mesh) {
  double a = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3d& p = mesh.vertices[t[0]];
    a += 0.5 * norm(cross(mesh.vertices[t[1]] - p, mesh.vertices[t[2]] - p));
  }
  return a;
}

/// World point p in the field's index space (origin at the mesh box centre, one unit a voxel).
inline Vec3d index_coords(const Vec3d& p, const Vec3d& origin, double inv_voxel) { return (p - origin) * inv_voxel; }

/// The built field and what queries read, shared read-only by every thread's queries.
struct Field {
  FloatGrid::Ptr sdf;
  Int32Grid::Ptr index;  ///< distance jobs with closest_triangle: the polygon index per voxel
  int order = 1, closest_steps = 2;
  double inv_voxel = 1;
  Vec3d origin, dom_lo, dom_hi;
  bool has_domain = false;
  double exterior_value = 0, interior_value = 0;
};

/// One thread's queries: its own value accessors (OpenVDB's accessors cache the path to the last
/// leaf and are not safe to share; a ConstUnsafeAccessor per thread over a grid nobody writes is)
/// and its counters.
class OpenVdbQueries final : public QueryState {
 public:
  explicit OpenVdbQueries(const Field& f) : f_(f), sdf_acc_(f.sdf->tree()) {
    if (f.index) index_acc_.emplace(f.index->tree());
  }

  bool inside(const Vec3d& p) override { return value_at(to_index(p)) < 0.0; }

  DistanceResult distance(const Vec3d& p) override {
    DistanceResult r;
    const Vec3d x = to_index(p);
    Vec3d g;
    const double d = value_and_gradient(x, &g);
    r.distance = d;
    r.normal = normalized(g);
    Vec3d q = p, gq = g;
    double dq = d;
    for (int s = 0; s < f_.closest_steps; ++s) {
      const double gn = norm(gq);
      if (!(gn > 0)) break;  // clamped region: no direction to follow, q stays put
      q -= gq * (dq / gn);
      if (s + 1 < f_.closest_steps) dq = value_and_gradient(to_index(q), &gq);
    }
    r.closest = q;
    if (index_acc_) {
      r.triangle = triangle_at(x);
      if (r.triangle < 0 && q != p) r.triangle = triangle_at(to_index(q));
    }
    return r;
  }

  std::vector<Counter> counters() const override {
    return {{"voxel_lookups", voxel_lookups_},
            {"gradient_evaluations", gradient_evaluations_},
            {"index_lookups", index_lookups_},
            {"clamped_samples", clamped_samples_}};
  }
  void reset_counters() override {
    voxel_lookups_ = gradient_evaluations_ = index_lookups_ = clamped_samples_ = 0;
  }

 private:
  Vec3d to_index(const Vec3d& p) const { return index_coords(p, f_.origin, f_.inv_voxel); }

  bool in_domain(const Vec3d& x) const {
    return f_.has_domain && x.x >= f_.dom_lo.x && x.y >= f_.dom_lo.y && x.z >= f_.dom_lo.z &&
           x.x <= f_.dom_hi.x && x.y <= f_.dom_hi.y && x.z <= f_.dom_hi.z;
  }

  /// Counts samples that read the clamped band value (beyond the band: a known error).
  void note_clamp(double v) {
    if (v >= f_.exterior_value * (1 - 1e-6) || v <= f_.interior_value * (1 - 1e-6)) ++clamped_samples_;
  }

  /// Sampled sdf at index-space point x (world units).
  double value_at(const Vec3d& x) {
    if (!in_domain(x)) {
      ++clamped_samples_;
      return f_.exterior_value;
    }
    double v;
    if (f_.order == 1) {
      float c[8];
      fetch8(x, c);
      const Vec3d f(x.x - std::floor(x.x), x.y - std::floor(x.y), x.z - std::floor(x.z));
      v = trilinear(c, f);
    } else {
      v = double(openvdb::tools::QuadraticSampler::sample(sdf_acc_, openvdb::Vec3R(x.x, x.y, x.z)));
      voxel_lookups_ += 27;
    }
    note_clamp(v);
    return v;
  }

  /// Sampled sdf and its gradient (world units, |g| ~ 1 in the band, 0 where clamped).
  double value_and_gradient(const Vec3d& x, Vec3d* g) {
    ++gradient_evaluations_;
    if (!in_domain(x)) {
      ++clamped_samples_;
      *g = Vec3d();
      return f_.exterior_value;
    }
    if (f_.order == 1) {
      float c[8];
      fetch8(x, c);
      const Vec3d f(x.x - std::floor(x.x), x.y - std::floor(x.y), x.z - std::floor(x.z));
      // c[(dx<<2)|(dy<<1)|dz]; analytic derivative of the trilinear blend.
      auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
      const double x00 = lerp(c[0], c[4], f.x), x01 = lerp(c[1], c[5], f.x);
      const double x10 = lerp(c[2], c[6], f.x), x11 = lerp(c[3], c[7], f.x);
      const double y0 = lerp(x00, x10, f.y), y1 = lerp(x01, x11, f.y);
      const double v = lerp(y0, y1, f.z);
      const double dz = y1 - y0;
      const double dy = lerp(x10 - x00, x11 - x01, f.z);
      const double dx = lerp(lerp(c[4] - c[0], c[6] - c[2], f.y), lerp(c[5] - c[1], c[7] - c[3], f.y), f.z);
      *g = Vec3d(dx, dy, dz) * f_.inv_voxel;
      note_clamp(v);
      return v;
    }
    const double h = 0.5;
    auto s = [&](double ox, double oy, double oz) {
      voxel_lookups_ += 27;
      return double(openvdb::tools::QuadraticSampler::sample(
          sdf_acc_, openvdb::Vec3R(x.x + ox, x.y + oy, x.z + oz)));
    };
    const double v = s(0, 0, 0);
    *g = Vec3d(s(h, 0, 0) - s(-h, 0, 0), s(0, h, 0) - s(0, -h, 0), s(0, 0, h) - s(0, 0, -h)) *
         (f_.inv_voxel / (2 * h));
    note_clamp(v);
    return v;
  }

  void fetch8(const Vec3d& x, float c[8]) {
    const Coord i0(int(std::floor(x.x)), int(std::floor(x.y)), int(std::floor(x.z)));
    auto& a = sdf_acc_;
    c[0] = a.getValue(i0);
    c[1] = a.getValue(i0.offsetBy(0, 0, 1));
    c[2] = a.getValue(i0.offsetBy(0, 1, 0));
    c[3] = a.getValue(i0.offsetBy(0, 1, 1));
    c[4] = a.getValue(i0.offsetBy(1, 0, 0));
    c[5] = a.getValue(i0.offsetBy(1, 0, 1));
    c[6] = a.getValue(i0.offsetBy(1, 1, 0));
    c[7] = a.getValue(i0.offsetBy(1, 1, 1));
    voxel_lookups_ += 8;
  }

  static double trilinear(const float c[8], const Vec3d& f) {
    auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
    const double x00 = lerp(c[0], c[4], f.x), x01 = lerp(c[1], c[5], f.x);
    const double x10 = lerp(c[2], c[6], f.x), x11 = lerp(c[3], c[7], f.x);
    return lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z);
  }

  std::int64_t triangle_at(const Vec3d& x) {
    if (!in_domain(x)) return -1;
    ++index_lookups_;
    const Coord c(int(std::floor(x.x + 0.5)), int(std::floor(x.y + 0.5)), int(std::floor(x.z + 0.5)));
    const openvdb::Int32 t = index_acc_->getValue(c);
    return t < 0 ? -1 : std::int64_t(t);
  }

  // parameters
  const Field& f_;
  FloatGrid::ConstUnsafeAccessor sdf_acc_;
  std::optional<Int32Grid::ConstUnsafeAccessor> index_acc_;
  std::uint64_t voxel_lookups_ = 0, gradient_evaluations_ = 0, index_lookups_ = 0, clamped_samples_ = 0;
};

class OpenVdbSdf final : public SharedStructureMethod<OpenVdbQueries> {
 public:
  explicit OpenVdbSdf(const Params& p)
      : voxel_rel_(p.get_real("voxel")),
        voxel_abs_(p.get_real("voxel_abs")),
        auto_band_(p.get("band") == "auto"),
        ex_band_(p.get_real("ex_band")),
        in_band_(p.get_real("in_band")),
        order_(int(p.get_int("order"))),
        closest_steps_(int(p.get_int("closest_steps"))),
        keep_index_(p.get_bool("closest_triangle")),
        renormalize_(p.get_bool("renormalize")),
        remove_intersecting_(p.get_bool("isect_cleanup")),
        max_voxels_(double(p.get_int("max_voxels"))),
        fit_(p.get_bool("fit")) {}

  void build(const Mesh& mesh, const BuildContext& ctx) override {
    // Without a triangle there is no surface to sample, whatever the query (the voxel size of
    // an empty box would otherwise make a misleading "too many voxels" refusal).
    if (mesh.triangles.empty()) throw InputError("openvdb: the mesh has no triangle");
    try {
      build_impl(mesh, ctx);
    } catch (const openvdb::Exception& e) {
      throw std::runtime_error(std::string("openvdb: ") + e.what());
    }
  }


  std::size_t structure_bytes() const override {
    std::size_t b = sizeof(*this);
    if (sdf_) b += std::size_t(sdf_->memUsage());
    if (index_) b += std::size_t(index_->memUsage());
    return b;
  }

  nlohmann::json info() const override {
    nlohmann::json j;
    j["voxel_size"] = voxel_;
    j["band"] = auto_band_ ? "auto" : "fixed";
    j["ex_band_voxels"] = ex_vox_;
    j["in_band_voxels"] = in_vox_;
    j["ex_band_world"] = ex_vox_ * voxel_;
    j["in_band_world"] = in_vox_ * voxel_;
    j["estimated_voxels"] = estimated_voxels_;
    j["voxel_requested"] = voxel_requested_;
    j["voxel_coarsened_to_fit"] = voxel_ > voxel_requested_;
    j["dense_query_box_voxels"] = dense_query_voxels_;
    j["active_voxels"] = sdf_ ? double(sdf_->activeVoxelCount()) : 0.0;
    j["leaf_nodes"] = sdf_ ? double(sdf_->tree().leafCount()) : 0.0;
    j["sdf_bytes"] = sdf_ ? double(sdf_->memUsage()) : 0.0;
    j["index_grid"] = bool(index_);
    j["index_bytes"] = index_ ? double(index_->memUsage()) : 0.0;
    j["exterior_value"] = exterior_value_;
    j["interior_value"] = interior_value_;
    return j;
  }

 private:
  std::unique_ptr<OpenVdbQueries> make_state() const override { return std::make_unique<OpenVdbQueries>(field_); }

  void build_impl(const Mesh& mesh, const BuildContext& ctx) {
    index_.reset();
    sdf_.reset();
    size_field(mesh, ctx);
    make_volume(mesh, ctx);
    publish_field();
    start_queries();
  }

  /// The voxel size, the band widths (voxels) and the estimated stored voxel count: the voxel
  /// asked for, coarsened until the field fits with fit=true; over the budget otherwise, InputError.
  void size_field(const Mesh& mesh, const BuildContext& ctx) {
    const Box3d mb = mesh.bounds();
    const double diag = mb.diagonal();
    voxel_ = voxel_abs_ > 0 ? voxel_abs_ : voxel_rel_ * mesh.average_edge_length();
    if (!(voxel_ > 0) || !std::isfinite(voxel_)) voxel_ = voxel_rel_ * diag / 100.0;  // all degenerate
    if (!(voxel_ > 0) || !std::isfinite(voxel_)) voxel_ = 1.0;  // a single point: any size will do
    origin_ = mb.empty() ? Vec3d() : (mb.lo + mb.hi) * 0.5;

    // ---- band widths (voxels) and the estimated stored voxel count, for a voxel size ----
    const Vec3d e = mb.extent();
    const double reach = auto_band_ && ctx.query_type == QueryType::distance && !ctx.query_bounds.empty()
                             ? surface_distance_bound(mesh, ctx.query_bounds)
                             : -1.0;
    const double area = surface_area(mesh);
    double max_index = 0;
    auto size_for = [&](double voxel) {
      voxel_ = voxel;
      inv_voxel_ = 1.0 / voxel_;
      ex_vox_ = ex_band_;
      in_vox_ = in_band_;
      if (reach >= 0) {
        const double half_min_extent = 0.5 * std::min({e.x, e.y, e.z});
        // +2 voxels: the trilinear stencil and a gradient step reach one voxel beyond p.
        ex_vox_ = std::max(ex_band_, reach * inv_voxel_ + 2.0);
        in_vox_ = std::max(in_band_, std::min(reach, half_min_extent) * inv_voxel_ + 2.0);
      }
      const double exw = ex_vox_ * voxel_, inw = in_vox_ * voxel_;
      const double leaf = 8 * voxel_;  // voxels are stored in 8^3 leaves: a band is rounded up
      const double shell = area * (exw + inw + 1.5 * leaf) + kPi * exw * exw * (e.x + e.y + e.z) +
                           4.0 / 3.0 * kPi * exw * exw * exw;
      const double dense = (e.x + 2 * exw + leaf) * (e.y + 2 * exw + leaf) * (e.z + 2 * exw + leaf);
      estimated_voxels_ = std::min(shell, dense) * inv_voxel_ * inv_voxel_ * inv_voxel_;
      max_index = std::max({e.x, e.y, e.z}) * 0.5 * inv_voxel_ + ex_vox_ + 16;
      return estimated_voxels_ <= max_voxels_ && max_index <= double(1 << 29);
    };
    voxel_requested_ = voxel_;
    // Over the budget: with fit=true (default) coarsen the voxel until the field fits, so that a
    // default run on a big model measures a field it can hold; with fit=false refuse.
    bool fits = size_for(voxel_);
    for (int step = 0; !fits && fit_ && step < 200; ++step) fits = size_for(voxel_ * 1.1);
    if (!fits) {
      std::ostringstream m;
      m << "openvdb: the distance field would hold about " << estimated_voxels_ << " voxels (voxel "
        << voxel_ << ", bands " << ex_vox_ << " out / " << in_vox_ << " in voxels), over max_voxels="
        << max_voxels_ << "; use a larger voxel, band=fixed with narrower bands, raise max_voxels, or fit=true";
      throw InputError(m.str());
    }
    dense_query_voxels_ = ctx.query_bounds.empty()
                              ? 0.0
                              : ctx.query_bounds.extent().x * ctx.query_bounds.extent().y *
                                    ctx.query_bounds.extent().z * inv_voxel_ * inv_voxel_ * inv_voxel_;
  }

  /// The signed distance field (and, for distance jobs with keep_index, the closest-polygon
  /// grid) of the mesh in index space, where polygon i is mesh triangle i. meshToVolume builds on
  /// TBB, which the job limits to its build threads (run_job).
  void make_volume(const Mesh& mesh, const BuildContext& ctx) {
    std::vector<openvdb::Vec3s> pts(mesh.vertices.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const Vec3d x = index_coords(mesh.vertices[i], origin_, inv_voxel_);
      pts[i] = openvdb::Vec3s(float(x.x), float(x.y), float(x.z));
    }
    std::vector<openvdb::Vec3I> tris(mesh.triangles.size());
    for (std::size_t i = 0; i < tris.size(); ++i)
      tris[i] = openvdb::Vec3I(mesh.triangles[i][0], mesh.triangles[i][1], mesh.triangles[i][2]);
    openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(pts, tris);

    auto xform = openvdb::math::Transform::createLinearTransform(voxel_);
    xform->postTranslate(openvdb::Vec3d(origin_.x, origin_.y, origin_.z));

    int flags = 0;
    if (!renormalize_) flags |= openvdb::tools::DISABLE_RENORMALIZATION;
    if (!remove_intersecting_) flags |= openvdb::tools::DISABLE_INTERSECTING_VOXEL_REMOVAL;
    const bool want_index = keep_index_ && ctx.query_type == QueryType::distance;
    if (want_index) index_ = Int32Grid::create(openvdb::Int32(openvdb::util::INVALID_IDX));
    openvdb::util::NullInterrupter interrupter;
    sdf_ = openvdb::tools::meshToVolume<FloatGrid>(interrupter, adapter, *xform, float(ex_vox_),
                                                  float(in_vox_), flags, index_.get());
    if (!sdf_) throw std::runtime_error("openvdb: meshToVolume returned no grid");
  }

  /// The field's values beyond its bands and its active domain, handed to the query states.
  void publish_field() {
    exterior_value_ = double(sdf_->background());
    interior_value_ = -in_vox_ * voxel_;
    // Points outside the active box (plus the stencil) read the background: answer them without
    // touching the tree, and without turning huge coordinates into integer overflow.
    const openvdb::CoordBBox bb = sdf_->evalActiveVoxelBoundingBox();
    has_domain_ = !bb.empty();
    if (has_domain_) {
      dom_lo_ = Vec3d(bb.min().x() - 2.0, bb.min().y() - 2.0, bb.min().z() - 2.0);
      dom_hi_ = Vec3d(bb.max().x() + 2.0, bb.max().y() + 2.0, bb.max().z() + 2.0);
    }
    field_.sdf = sdf_;
    field_.index = index_;
    field_.order = order_;
    field_.closest_steps = closest_steps_;
    field_.inv_voxel = inv_voxel_;
    field_.origin = origin_;
    field_.dom_lo = dom_lo_;
    field_.dom_hi = dom_hi_;
    field_.has_domain = has_domain_;
    field_.exterior_value = exterior_value_;
    field_.interior_value = interior_value_;
  }

  double voxel_rel_, voxel_abs_;
  bool auto_band_;
  double ex_band_, in_band_;
  int order_, closest_steps_;
  bool keep_index_, renormalize_, remove_intersecting_;
  double max_voxels_;
  bool fit_;
  double voxel_requested_ = 0;

  // the structure (grids before their accessors: accessors are destroyed first)
  FloatGrid::Ptr sdf_;
  Int32Grid::Ptr index_;
  double voxel_ = 1, inv_voxel_ = 1;
  Vec3d origin_, dom_lo_, dom_hi_;
  bool has_domain_ = false;
  double ex_vox_ = 0, in_vox_ = 0, exterior_value_ = 0, interior_value_ = 0;
  double estimated_voxels_ = 0, dense_query_voxels_ = 0;
  Field field_;  // what queries read, set at the end of build
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_openvdb(bvhbench::Registry& r) {
  using namespace bvhbench;
  openvdb::initialize();
  note_library_version("openvdb", OPENVDB_LIBRARY_VERSION_STRING);
  MethodInfo m = MethodInfo::named("openvdb",
                                   "OpenVDB signed distance field (meshToVolume): sampled distance, gradient normal and "
                                   "projection, inside by sign, closest triangle from the polygon-index grid");
  // Capabilities, said once here (false unless set).
  m.caps.inside = true; m.caps.distance = true; m.caps.closest_triangle = true;
  m.caps.concurrent_queries = true;  // per-thread value accessors over grids nobody writes
  m.caps.build_threads = BuildThreads::job;  // builds on the job's threads (TBB or the device's)
  // None: our counters count our own samples of the grid, whose values meshToVolume computes in
  // header templates compiled here (no run-time CPU dispatch: OPENVDB_USE_SSE42/AVX are
  // compile-time switches, off; libopenvdb itself has no CPUID or ifunc). Each voxel's distance
  // is a minimum over triangles, the same however TBB splits the work.
  m.machine_dependent_counters = {};
  m.params = {
      {"voxel", ParamType::real, ParamRole::build, "1.0", "voxel size relative to the mean edge length", {}, 1e-6, 1e6},
      {"voxel_abs", ParamType::real, ParamRole::build, "0", "absolute voxel size (world units); overrides voxel when > 0", {}, 0.0, 1e308},
      {"band", ParamType::choice, ParamRole::build, "auto",
       "auto: narrow band for inside jobs, band reaching the whole query box for distance jobs; "
       "fixed: ex_band/in_band as given",
       {"auto", "fixed"}},
      {"ex_band", ParamType::real, ParamRole::build, "3", "exterior band width in voxels (the minimum under band=auto)", {}, 1.0, 1e6},
      {"in_band", ParamType::real, ParamRole::build, "3", "interior band width in voxels (the minimum under band=auto)", {}, 1.0, 1e6},
      {"order", ParamType::integer, ParamRole::query, "1", "sampler: 1 trilinear, 2 triquadratic", {}, 1, 2},
      {"closest_steps", ParamType::integer, ParamRole::query, "2", "gradient projections toward the surface for the closest point", {}, 0, 16},
      {"closest_triangle", ParamType::boolean, ParamRole::build, "true", "keep the polygon-index grid (distance jobs) to report the closest triangle", {}},
      {"renormalize", ParamType::boolean, ParamRole::build, "true", "meshToVolume renormalisation (off: DISABLE_RENORMALIZATION)", {}},
      {"isect_cleanup", ParamType::boolean, ParamRole::build, "true",
       "meshToVolume removal of self-intersection voxels (off: DISABLE_INTERSECTING_VOXEL_REMOVAL)", {}},
      {"max_voxels", ParamType::integer, ParamRole::build, "50000000", "budget of stored voxels (estimated before building; ~200 MB per grid)", {}, 1, 1e15},
      {"fit", ParamType::boolean, ParamRole::build, "true", "over max_voxels: coarsen the voxel until the field fits (false: refuse)", {}},
  };
  // The band (band=auto) and the dense-grid estimate are sized from the job's query points.
  m.sharing = [](const Params&) { return StructureSharing::job_alone; };
  // meshToVolume signs its field by flood-filling the outside from the box: what the flood
  // cannot reach is inside, the union of the shells, sampled at the voxel. It asks for a
  // watertight mesh; on one not consistently oriented (a flipped patch) the nonzero winding
  // number is not defined, so its contract asks for that too.
  m.inside = {{{}, {InsideRule::nonzero_winding, true, 0.5, InputContract::closed_oriented}, ""}};
  m.create = [](const Params& p) { return std::make_unique<OpenVdbSdf>(p); };
  r.add(std::move(m));
}
