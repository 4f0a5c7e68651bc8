#include "methods/ebp_octree/build/polytope.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ebp {

Polytope Polytope::box(const Vec3d& lo, const Vec3d& hi) {
  Polytope p;
  const Vec3d v[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z},
                      {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {lo.x, hi.y, hi.z}, {hi.x, hi.y, hi.z}};
  // Outward counter-clockwise faces.
  const int f[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (auto& q : f) p.faces_.push_back({v[q[0]], v[q[1]], v[q[2]], v[q[3]]});
  return p;
}

void Polytope::clip(const Vec3d& n, double d) {
  if (faces_.empty()) return;
  double scale = 0;
  for (auto& f : faces_)
    for (auto& v : f) scale = std::max(scale, std::fabs(dot(n, v)));
  const double tol = 1e-13 * (scale + std::fabs(d));
  // Capacities reserved up front (a face gains at most one vertex; the cap at most two per face):
  // the build clips ~1 polytope per node, and vector growth was ~3 % of the external build.
  std::vector<std::vector<Vec3d>> out;
  out.reserve(faces_.size() + 1);
  std::vector<Vec3d> cap;
  cap.reserve(2 * faces_.size());
  bool any_cut = false;
  for (auto& f : faces_) {
    std::vector<Vec3d> g;
    const std::size_t m = f.size();
    g.reserve(m + 1);
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3d& P = f[i];
      const Vec3d& Q = f[(i + 1) % m];
      const double sp = dot(n, P) - d, sq = dot(n, Q) - d;
      const bool pin = sp <= tol;
      if (pin) g.push_back(P);
      if (sp > tol) any_cut = true;
      if (std::fabs(sp) <= tol) cap.push_back(P);
      if ((sp < -tol && sq > tol) || (sp > tol && sq < -tol)) {
        const Vec3d X = P + (Q - P) * (sp / (sp - sq));
        g.push_back(X);
        cap.push_back(X);
      }
    }
    if (g.size() >= 3) out.push_back(std::move(g));
  }
  if (!any_cut) return;  // the plane does not cut: unchanged
  faces_ = std::move(out);
  if (faces_.empty()) return;
  // The cap: points on the plane, ordered counter-clockwise around +n (outward).
  if (cap.size() >= 3) {
    Vec3d c{};
    for (auto& p : cap) c += p;
    c = c / double(cap.size());
    const Vec3d nn = bvhbench::normalized(n);
    Vec3d u = std::fabs(nn.x) < 0.9 ? cross(nn, Vec3d(1, 0, 0)) : cross(nn, Vec3d(0, 1, 0));
    u = bvhbench::normalized(u);
    const Vec3d w = cross(nn, u);
    std::vector<std::pair<double, Vec3d>> ang;
    ang.reserve(cap.size());
    for (auto& p : cap) ang.push_back({std::atan2(dot(p - c, w), dot(p - c, u)), p});
    std::sort(ang.begin(), ang.end(), [](auto& a, auto& b) { return a.first < b.first; });
    std::vector<Vec3d> poly;
    poly.reserve(cap.size());
    const double merge = 1e-12 * (scale + 1e-300);
    for (auto& a : ang)
      if (poly.empty() || squared_norm(a.second - poly.back()) > merge * merge) poly.push_back(a.second);
    while (poly.size() > 1 && squared_norm(poly.front() - poly.back()) <= merge * merge) poly.pop_back();
    if (poly.size() >= 3) faces_.push_back(std::move(poly));
  }
}

std::vector<Vec3d> Polytope::vertices() const {
  std::vector<Vec3d> v;
  for (auto& f : faces_) v.insert(v.end(), f.begin(), f.end());
  return v;
}

double Polytope::volume() const {
  if (faces_.empty()) return 0;
  Vec3d o = faces_[0][0];
  double vol = 0;
  for (auto& f : faces_)
    for (std::size_t i = 1; i + 1 < f.size(); ++i) vol += dot(f[0] - o, cross(f[i] - o, f[i + 1] - o));
  return std::max(0.0, vol / 6.0);
}

double Polytope::support(const Vec3d& n) const {
  double s = -std::numeric_limits<double>::infinity();
  for (auto& f : faces_)
    for (auto& v : f) s = std::max(s, dot(n, v));
  return s;
}

}  // namespace ebp
