// The `haptic` query kind: a simulated 1 kHz haptic probe (the workload the EBP-Octree paper
// targets), its contact-only variant `contact`, and the triangle grid they use to follow the
// surface.
//
// The path is a sequence of contact episodes of fixed length (haptic_layout). In each:
//  - approach: from free space (approach_mm off the surface, behind the first contact point)
//    along a smooth curve whose velocity ends equal to the sliding velocity;
//  - contact: the probe slides over the surface like a haptic proxy. Each sample moves the
//    probe along its heading in the tangent plane, projects the predicted position onto the
//    mesh (exact closest point, from the grid) and puts the probe at a signed offset along the
//    outward direction of that closest point. The offset varies smoothly inside the contact
//    band (+-band_mm: slightly outside, slightly penetrating); the heading turns smoothly (an
//    Ornstein-Uhlenbeck angular velocity) and the speed varies below slide_speed. A step is
//    never longer than max_speed / rate_hz (where the closest point jumps, across a concave
//    crease or a thin part, the probe is held to that step and catches up);
//  - leave: away along the last outward direction, velocity continuous, back to free space.
// The `contact` kind is the same path without the approach and leave phases: every sample is in
// the band (the regime a device pressed on the surface lives in), episodes start on a new
// surface point. Its random draws are the haptic path's, so the two share their contact phases.
// Scale: the mesh's bounding-box diagonal is taken as model_size_m metres (30 cm by default),
// so a hand at 0.5 m/s moves at most 0.5 / 0.3 / 1000 = 0.17% of the diagonal per sample.
//
// Closest points: a dense uniform grid of triangle ids built once (cells at least as large as
// the contact band). Each contact sample has a distance bound for free (the previous closest
// point is on the surface), so it only tests the triangles of the few cells overlapping the
// box p +- bound. Exact, and at 30M triangles ~ a few hundred triangle tests per sample. On a
// paged mesh (`bvhbench queries --memory-budget`) the grid's ids are paged too; ties go to the
// lower triangle id, so the path is the same bytes whatever the grid's cells.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "harness/core/correctly_rounded.hpp"
#include "harness/core/query_kinds_detail.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/rng.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench::query_kinds_detail {

namespace {
constexpr double kTwoPi = 6.283185307179586476925;
double smoothstep(double x) { return x * x * (3 - 2 * x); }
}  // namespace

// ---------------------------------------------------------------------------------------------
// TriangleGrid
// ---------------------------------------------------------------------------------------------

int TriangleGrid::cell_coord(double x, int axis) const {
  const double c = std::floor((x - lo_[axis]) / h_);
  if (!(c > 0)) return 0;  // also NaN
  if (c >= n_[axis] - 1) return n_[axis] - 1;
  return int(c);
}

TriangleGrid::TriangleGrid(const TriangleSource& source, double min_cell, std::size_t max_cells, Progress* progress)
    : source_(source) {
  const ScratchSpace* scratch = source.scratch();
  // Paged: the offsets take a sixteenth of the budget, a slab of ids being filled a quarter and
  // the cells of each triangle, kept for the slab passes, a sixteenth; once those are gone, the
  // cache of ids a sixteenth (the source's own caches hold the rest).
  if (scratch) max_cells = std::max<std::size_t>(1, std::min(max_cells, scratch->budget_bytes / 16 / sizeof(std::uint32_t)));
  Box3d box = source.summary().bounds;
  if (box.empty() || source.num_triangles() == 0)
    throw InputError(source.path() + ": cannot build a grid over an empty mesh");
  const double diag = box.diagonal();
  const double pad = diag > 0 ? diag * 1e-9 : 1e-9;
  box.lo -= Vec3d(pad, pad, pad);
  box.hi += Vec3d(pad, pad, pad);
  lo_ = box.lo;
  const Vec3d ext = box.extent();
  h_ = std::max({min_cell, 2 * source.average_edge_length(), diag * 1e-6, 1e-300});
  for (;;) {
    std::size_t cells = 1;
    for (int i = 0; i < 3; ++i) {
      n_[i] = std::max(1, int(std::min(std::ceil(ext[i] / h_), 1e9)));
      cells *= std::size_t(n_[i]);
    }
    if (cells <= max_cells) break;
    h_ *= 1.25;
  }
  const std::size_t slab_ids = scratch ? std::max<std::size_t>(1, scratch->budget_bytes / 4 / sizeof(std::uint32_t))
                                       : std::numeric_limits<std::size_t>::max();
  fill(slab_ids, progress);
}

void TriangleGrid::cell_range(std::uint32_t t, int lo[3], int hi[3]) const {
  const std::array<Vec3d, 3> v = source_.corners(t);
  for (int i = 0; i < 3; ++i) {
    const int a = cell_coord(v[0][i], i), b = cell_coord(v[1][i], i), c = cell_coord(v[2][i], i);
    lo[i] = std::min({a, b, c});
    hi[i] = std::max({a, b, c});
  }
}

std::size_t TriangleGrid::linear(int x, int y, int z) const { return (std::size_t(z) * n_[1] + y) * n_[0] + x; }

// A pass to count each cell's triangles, then one pass per slab (a run of cells whose ids fit
// `slab_ids`; in memory, one slab for all) to write their ids, in increasing order within each
// cell. Each pass works out a triangle's cells from its corners again: nothing per vertex or per
// triangle is kept between passes, so the build holds the offsets and one slab of ids alone.
void TriangleGrid::fill(std::size_t slab_ids, Progress* progress) {
  // Paged, every triangle's corners are three page look-ups: the count pass keeps each triangle's
  // first and last cell (8 bytes) in a scratch file that the slab passes read in order instead.
  const ScratchSpace* scratch = source_.scratch();
  std::unique_ptr<ScratchArray<CellSpan>> spans;
  if (scratch) spans = std::make_unique<ScratchArray<CellSpan>>(scratch->dir, "triangle grid spans", scratch->budget_bytes / 16);
  count_cells(spans.get(), progress);
  const std::size_t cells = num_cells();
  std::vector<std::size_t> slab_end;  // slab k is cells [slab_end[k - 1], slab_end[k])
  for (std::size_t c0 = 0; c0 < cells;) {
    std::size_t c1 = c0 + 1;  // a cell fuller than a slab is a slab of its own
    while (c1 < cells && offsets_[c1 + 1] - offsets_[c0] <= slab_ids) ++c1;
    slab_end.push_back(c0 = c1);
  }
  slabs_ = slab_end.size();
  if (scratch)
    paged_ids_ = std::make_unique<ScratchArray<std::uint32_t>>(scratch->dir, "triangle grid ids",
                                                                scratch->budget_bytes / 16);
  // Reserved once for the largest slab: growing it between slabs would hold two at once.
  std::vector<std::uint32_t> slab;
  std::uint32_t largest = 0;
  for (std::size_t k = 0, c0 = 0; k < slab_end.size(); c0 = slab_end[k++])
    largest = std::max(largest, offsets_[slab_end[k]] - offsets_[c0]);
  slab.reserve(largest);
  for (std::size_t k = 0, c0 = 0; k < slab_end.size(); c0 = slab_end[k++]) {
    write_slab(c0, slab_end[k], spans.get(), slab, progress);
    if (paged_ids_) paged_ids_->append(slab.data(), slab.size());
  }
  spans.reset();  // before the ids' cache comes
  if (paged_ids_) {
    paged_ids_->finish();
  } else {
    ids_ = std::move(slab);
  }
  // Every offset is now its cell's end: shifted by one, each is its cell's start again.
  for (std::size_t c = cells; c > 0; --c) offsets_[c] = offsets_[c - 1];
  offsets_[0] = 0;
}

// Each cell's count, then offsets_[c] = the start of cell c (offsets_[#cells] = all references).
// `spans`, if given, gets every triangle's first and last cell, in triangle order.
void TriangleGrid::count_cells(ScratchArray<CellSpan>* spans, Progress* progress) {
  const std::size_t cells = num_cells();
  offsets_.assign(cells + 1, 0);
  const auto nt = std::uint32_t(source_.num_triangles());
  std::uint64_t refs = 0;
  for (std::uint32_t t = 0; t < nt; ++t) {
    int lo[3], hi[3];
    cell_range(t, lo, hi);
    if (spans) spans->push_back({std::uint32_t(linear(lo[0], lo[1], lo[2])), std::uint32_t(linear(hi[0], hi[1], hi[2]))});
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) ++offsets_[linear(x, y, z)];
    refs += std::uint64_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    if (progress && (t & 0xfffff) == 0) progress->add(double(0x100000));
  }
  if (refs >= 0xffffffffull) throw InputError(source_.path() + ": too many triangle-cell pairs for the grid");
  if (spans) spans->finish();
  std::uint32_t sum = 0;
  for (std::size_t c = 0; c < cells; ++c) sum += std::exchange(offsets_[c], sum);
  offsets_[cells] = sum;
}

// The ids of cells [c0, c1) into `slab`, from one pass over the triangles. The offsets of those
// cells are their write cursors: each ends at its cell's end (the next cell's start).
void TriangleGrid::write_slab(std::size_t c0, std::size_t c1, const ScratchArray<CellSpan>* spans,
                              std::vector<std::uint32_t>& slab, Progress* progress) {
  const std::uint32_t base = offsets_[c0];
  slab.assign(offsets_[c1] - base, 0);
  const auto nt = std::uint32_t(source_.num_triangles());
  const std::size_t row = std::size_t(n_[0]), layer = row * std::size_t(n_[1]);
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (progress && (t & 0xfffff) == 0) progress->add(double(0x100000) / double(slabs_));
    int lo[3], hi[3];
    if (spans) {
      const CellSpan span = (*spans)[t];
      if (span.last < c0 || span.first >= c1) continue;
      auto cell_of = [&](std::size_t c, int xyz[3]) {
        xyz[0] = int(c % row);
        xyz[1] = int(c % layer / row);
        xyz[2] = int(c / layer);
      };
      cell_of(span.first, lo);
      cell_of(span.last, hi);
    } else {
      cell_range(t, lo, hi);
      if (linear(hi[0], hi[1], hi[2]) < c0 || linear(lo[0], lo[1], lo[2]) >= c1) continue;
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const std::size_t c = linear(x, y, z);
          if (c >= c0 && c < c1) slab[offsets_[c]++ - base] = t;
        }
  }
}

bool TriangleGrid::closest(const Vec3d& p, double r, Hit* hit) const {
  int lo[3], hi[3], home[3];
  for (int i = 0; i < 3; ++i) {
    lo[i] = cell_coord(p[i] - r, i);
    hi[i] = cell_coord(p[i] + r, i);
    home[i] = cell_coord(p[i], i);
  }
  double best2 = std::numeric_limits<double>::infinity();
  bool found = false;
  auto scan = [&](int x, int y, int z) {
    const std::size_t c = linear(x, y, z);
    for (std::uint32_t k = offsets_[c]; k < offsets_[c + 1]; ++k) {
      const std::uint32_t t = paged_ids_ ? (*paged_ids_)[k] : ids_[k];
      const std::array<Vec3d, 3> v = source_.corners(t);
      const Vec3d &a = v[0], &b = v[1], &cc = v[2];
      // The triangle's box first: most triangles of a visited cell are farther than the best.
      double box2 = 0;
      for (int i = 0; i < 3; ++i) {
        const double mn = std::min({a[i], b[i], cc[i]}), mx = std::max({a[i], b[i], cc[i]});
        const double d = std::max({mn - p[i], 0.0, p[i] - mx});
        box2 += d * d;
      }
      if (box2 > best2) continue;
      const Vec3d q = closest_point_on_triangle(p, a, b, cc);
      const double d2 = squared_norm(q - p);
      ++tested_;
      // Ties go to the lower triangle id, so the answer does not depend on visit order.
      if (d2 < best2 || (d2 == best2 && t < hit->triangle)) {
        best2 = d2;
        hit->point = q;
        hit->triangle = t;
        found = true;
      }
    }
  };
  // The cell holding p first (it usually holds the answer), then the others that can still
  // hold something closer than the best so far.
  const bool home_in_box = home[0] >= lo[0] && home[0] <= hi[0] && home[1] >= lo[1] &&
                           home[1] <= hi[1] && home[2] >= lo[2] && home[2] <= hi[2];
  if (home_in_box) scan(home[0], home[1], home[2]);
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) {
        if (home_in_box && x == home[0] && y == home[1] && z == home[2]) continue;
        const int xyz[3] = {x, y, z};
        double cell2 = 0;
        for (int i = 0; i < 3; ++i) {
          const double clo = lo_[i] + h_ * xyz[i], chi = clo + h_;
          // Border cells extend to infinity (cell_coord clamps), so never cull them by box.
          const double d = std::max({(xyz[i] > 0 ? clo : -1e300) - p[i], 0.0,
                                     p[i] - (xyz[i] < n_[i] - 1 ? chi : 1e300)});
          cell2 += d * d;
        }
        if (cell2 > best2) continue;
        scan(x, y, z);
      }
  if (found) hit->distance = std::sqrt(best2);
  return found;
}

// ---------------------------------------------------------------------------------------------
// the haptic path
// ---------------------------------------------------------------------------------------------

HapticLayout haptic_layout(const TriangleSource& mesh, const Params& p, bool approach_and_leave) {
  // Each value is in its declared range (query_kinds.cpp: lengths, speeds and times > 0);
  // what is checked here is how they bound each other.
  auto get = [&](const char* key) { return p.get_real(key); };
  const double model = get("model_size_m"), rate = get("rate_hz"), vmax = get("max_speed");
  const double slide = get("slide_speed"), band_mm = get("band_mm"), contact_ms = get("contact_ms");
  const double diag = mesh.summary().bounds.diagonal();
  if (!(diag > 0) || !std::isfinite(diag))
    throw InputError(mesh.path() + ": the mesh has no extent to move a probe over");
  HapticLayout L;
  L.units_per_metre = diag / model;
  L.max_step = vmax / rate * L.units_per_metre;
  L.band = band_mm * 1e-3 * L.units_per_metre;
  L.contact = std::max<std::size_t>(2, std::size_t(std::llround(contact_ms * 1e-3 * rate)));
  if (!approach_and_leave) {
    // Contact only: the probe never leaves the band, so sliding alone must respect max_speed.
    if (slide > vmax) throw InputError("query kind 'contact': slide_speed must not exceed max_speed");
    return L;
  }
  const double vapp = get("approach_speed"), d0_mm = get("approach_mm");
  if (slide + vapp > vmax)
    throw InputError("query kind 'haptic': slide_speed + approach_speed must not exceed max_speed");
  L.approach_distance = d0_mm * 1e-3 * L.units_per_metre;
  // Smoothstep's peak rate is 1.5 / T: T = 1.5 d0 / approach_speed keeps the normal speed
  // below approach_speed.
  const double t_app = 1.5 * d0_mm * 1e-3 / vapp;
  L.approach = L.leave = std::max<std::size_t>(1, std::size_t(std::ceil(t_app * rate)));
  return L;
}

namespace {

/// Where the probe is and where it goes, carried from one step of an episode to the next.
struct ProbeState {
  Vec3d surf;   // the closest surface point, followed along the path
  Vec3d nrm;    // the outward direction at surf
  Vec3d dir;    // the heading, in the tangent plane
  Vec3d probe;  // the probe's position
  Vec3d vel;    // its velocity
  double omega = 0;  // the heading's angular velocity
};

/// An episode's smooth speed along the surface and offset across the band (random phases).
struct EpisodeMotion {
  double slide = 0, band = 0;
  double fs = 0, ps = 0, f1 = 0, p1 = 0, f2 = 0, p2 = 0;
  // Correctly rounded sin/cos: the path is the same bytes on every machine (correctly_rounded.hpp).
  double speed_at(double t) const { return slide * (0.6 + 0.4 * correctly_rounded::sin(kTwoPi * fs * t + ps)); }
  double offset_at(double t) const {
    return band * 0.9 * (0.6 * correctly_rounded::sin(kTwoPi * f1 * t + p1) + 0.4 * correctly_rounded::sin(kTwoPi * f2 * t + p2));
  }
};

/// First contact: an area-weighted surface point, outward along its face normal, and a random
/// heading in the tangent plane.
ProbeState first_contact(const TriangleSource& mesh, const AreaSampler& sampler, Rng& rng) {
  ProbeState s;
  const std::uint32_t t0 = sampler.pick(rng.uniform());
  const auto [a, b, c] = mesh.corners(t0);
  const double r1 = rng.uniform(), r2 = rng.uniform();
  s.surf = uniform_in_triangle(a, b, c, r1, r2);
  s.nrm = triangle_normal(a, b, c);
  do {
    s.dir = Vec3d(rng.normal(), rng.normal(), rng.normal());
    s.dir -= s.nrm * dot(s.dir, s.nrm);
  } while (!(norm(s.dir) > 1e-6));
  s.dir = normalized(s.dir);
  return s;
}

EpisodeMotion draw_motion(Rng& rng, double slide, double band) {
  EpisodeMotion m;
  m.slide = slide;
  m.band = band;
  m.fs = rng.uniform(0.2, 0.8);
  m.ps = rng.uniform(0, kTwoPi);
  m.f1 = rng.uniform(0.3, 1.0);
  m.p1 = rng.uniform(0, kTwoPi);
  m.f2 = rng.uniform(1.5, 4.0);
  m.p2 = rng.uniform(0, kTwoPi);
  return m;
}

/// The constants every step of every episode reads.
struct PathSettings {
  HapticLayout L;
  double dt = 0, turn_rate = 0;
  double tau = 0.3;  // s, correlation time of the heading's angular velocity
  double T = 0;      // approach and leave duration (0: contact only)
  double tiny = 0;   // a distance below any the mesh resolves
};

/// One step of the contact phase at time t: turn the heading, predict, follow the surface to the
/// closest point near the prediction, and move within the band (at most L.max_step).
void slide_step(const PathSettings& S, const TriangleSource& mesh, const TriangleGrid& grid, const EpisodeMotion& motion,
                Rng& rng, double t, ProbeState& s) {
  const double dt = S.dt, tau = S.tau;
  s.omega += -s.omega * dt / tau + S.turn_rate * std::sqrt(2 * dt / tau) * rng.normal();
  const double ang = s.omega * dt;
  s.dir = s.dir * correctly_rounded::cos(ang) + cross(s.nrm, s.dir) * correctly_rounded::sin(ang);
  Vec3d tangent = s.dir - s.nrm * dot(s.dir, s.nrm);
  if (norm(tangent) > 1e-9) s.dir = normalized(tangent);
  s.vel = s.dir * motion.speed_at(t);
  const Vec3d pred = s.probe + s.vel * dt;
  TriangleGrid::Hit hit{};
  hit.triangle = ~std::uint32_t(0);
  // The previous closest point is on the surface: the distance is at most r.
  const double r = norm(pred - s.surf) * (1 + 1e-9) + S.tiny;
  if (grid.closest(pred, r, &hit)) {
    const Vec3d u = pred - hit.point;
    const double d = norm(u);
    const auto [a, b, c] = mesh.corners(hit.triangle);
    const Vec3d nf = triangle_normal(a, b, c);
    if (d > S.L.band * 1e-6) {
      s.nrm = u / d * (dot(u, nf) >= 0 ? 1.0 : -1.0);
    } else if (norm(nf) > 0) {
      s.nrm = nf;
    }
    s.surf = hit.point;
  }
  Vec3d next = s.surf + s.nrm * motion.offset_at(t);
  const Vec3d step = next - s.probe;
  const double len = norm(step);
  if (len > S.L.max_step) next = s.probe + step * (S.L.max_step / len);
  s.probe = next;
}

/// One episode appended to out (until it holds n points): approach, contact, leave.
void append_episode(const PathSettings& S, const TriangleSource& mesh, const AreaSampler& sampler, const TriangleGrid& grid,
                    double slide, Rng& rng, std::size_t n, std::vector<Vec3d>& out) {
  const HapticLayout& L = S.L;
  const double dt = S.dt, T = S.T;
  ProbeState s = first_contact(mesh, sampler, rng);
  const EpisodeMotion motion = draw_motion(rng, slide, L.band);
  s.probe = s.surf + s.nrm * motion.offset_at(0);
  const Vec3d vel0 = s.dir * motion.speed_at(0);

  // Approach: tau runs from T down to dt; at tau = 0 the probe is at the first contact.
  for (std::size_t k = 0; k < L.approach && out.size() < n; ++k) {
    const double tau_k = double(L.approach - k) * dt;
    out.push_back(s.probe - vel0 * (tau_k - tau_k * tau_k / (2 * T)) +
                  s.nrm * (L.approach_distance * smoothstep(tau_k / T)));
  }
  // Contact: slide, following the surface.
  s.vel = vel0;
  for (std::size_t k = 0; k < L.contact && out.size() < n; ++k) {
    if (k > 0) slide_step(S, mesh, grid, motion, rng, double(k) * dt, s);
    out.push_back(s.probe);
  }
  // Leave: velocity continuous, out along the last outward direction.
  const Vec3d start = s.probe;
  for (std::size_t k = 1; k <= L.leave && out.size() < n; ++k) {
    const double t = double(k) * dt;
    out.push_back(start + s.vel * (t - t * t / (2 * T)) + s.nrm * (L.approach_distance * smoothstep(t / T)));
  }
}

// Both kinds' paths: with approach_and_leave false the episodes are their contact phase alone
// (the random draws are the same, so the haptic path's bytes do not depend on this option).
std::vector<Vec3d> probe_path(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& params,
                              bool approach_and_leave) {
  PathSettings S;
  S.L = haptic_layout(mesh, params, approach_and_leave);
  S.dt = 1.0 / params.get_real("rate_hz");
  S.turn_rate = params.get_real("turn_rate");
  S.T = double(S.L.approach) * S.dt;
  S.tiny = mesh.summary().bounds.diagonal() * 1e-12;
  const double slide = params.get_real("slide_speed") * S.L.units_per_metre;  // units / s
  AreaSampler sampler(mesh);
  Progress progress_grid(std::string("haptic: triangle grid") + (mesh.scratch() ? " (paged)" : ""),
                         2.0 * double(mesh.num_triangles()), mesh.num_triangles() >= 2000000);
  const TriangleGrid grid(mesh, S.L.band, std::size_t(1) << 26, &progress_grid);
  progress_grid.finish();
  Progress progress("haptic path", double(n), n >= 200000);
  Rng rng(seed);
  std::vector<Vec3d> out;
  out.reserve(n);
  while (out.size() < n) {
    append_episode(S, mesh, sampler, grid, slide, rng, n, out);
    progress.update(double(out.size()));
  }
  progress.finish();
  return out;
}

}  // namespace

std::vector<Vec3d> haptic_path(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& params) {
  return probe_path(mesh, n, seed, params, true);
}

std::vector<Vec3d> contact_path(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& params) {
  return probe_path(mesh, n, seed, params, false);
}

}  // namespace bvhbench::query_kinds_detail
