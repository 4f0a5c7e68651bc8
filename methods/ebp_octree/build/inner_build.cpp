// One grey inner node (build_parts.hpp, build_inner): planes chosen among its children's, offset
// to the support of the children's bounding volumes (vertices of cell box ∩ planes).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/build/plane_fit.hpp"
#include "methods/ebp_octree/build/polytope.hpp"

namespace ebp::detail {

void build_inner(const BuildContext& ctx, Octcode code, NodeTmp* const children[8], NodeTmp* tmp) {
  Vec3d lo, hi;
  ctx.f.cell_box(code, &lo, &hi);
  const double csl = hi.x - lo.x;
  std::vector<Vec3d> pts;
  std::vector<Vec3d> cand;
  for (int o = 0; o < 8; ++o) {
    NodeTmp* ct = children[o];
    if (!ct) continue;
    pts.insert(pts.end(), ct->poly.begin(), ct->poly.end());
    for (const Plane& p : ct->planes) cand.push_back({double(p.n[0]), double(p.n[1]), double(p.n[2])});
    std::vector<Vec3d>().swap(ct->poly);  // children's volumes are no longer needed
  }
  struct Scored { Plane p; double cut; Vec3d n; };
  std::vector<Scored> sc;
  for (const Vec3d& nn : cand) {
    Plane p;
    make_plane(ctx, nn, pts, &p);
    Vec3d nw; double d;
    plane_world(ctx, p, &nw, &d);
    const double cut = box_support(lo, hi, nw) - d;
    if (cut > 1e-4 * csl) sc.push_back({p, cut, nw});
  }
  std::stable_sort(sc.begin(), sc.end(), [](const Scored& x, const Scored& y) { return x.cut > y.cut; });
  NodeTmp& tm = *tmp;
  tm.planes.clear();
  std::vector<Vec3d> chosen;
  for (const Scored& s : sc) {
    if (int(tm.planes.size()) >= ctx.max_planes) break;
    bool close = false;
    for (const Vec3d& c : chosen)
      if (dot(c, s.n) >= ctx.cos_cluster) { close = true; break; }
    if (close) continue;
    chosen.push_back(s.n);
    tm.planes.push_back(s.p);
  }
  Polytope poly = Polytope::box(lo, hi);
  for (const Plane& p : tm.planes) {
    Vec3d nw; double d;
    plane_world(ctx, p, &nw, &d);
    poly.clip(nw, d);
  }
  tm.poly = poly.vertices();
  if (tm.poly.empty()) tm.poly = Polytope::box(lo, hi).vertices();
  tm.volume = poly.volume();
  tm.box_volume = csl * csl * csl;
}

}  // namespace ebp::detail
