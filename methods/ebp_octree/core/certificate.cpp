// The distance certificate (certificate.hpp).
//
// Why S holds q's closest triangle. Let tol bound the rounding of a computed point-triangle
// distance d_c (|d_c - d| <= tol, d the exact one), best = d_c(p, W) for p's winner W, and S the
// triangles with d_c(p, X) <= T' = best + 2r + 5 tol, all of which the relaxed branch and bound
// offered (it prunes only what is strictly beyond its radius, which stays >= T'). For q with
// |q - p| <= r and X not in S: d_c(q, X) >= d(q, X) - tol >= d(p, X) - r - tol > T' - r - 2 tol =
// best + r + 3 tol, while d_c(q, W) <= d(q, W) + tol <= d(p, W) + r + tol <= best + r + 2 tol.
// So X is strictly worse than W at q and the lexicographic minimum over S is the mesh's.
//
// Why the scan's pre-test only prunes. For a triangle with float face normal n and float edge
// normals m_e (in the face plane, outward; both as rounded from double, so unit and orthogonal to
// 1e-7), every point x of the triangle has |(n.(x - p)) - d| <= e_h and m_e.(x - p) - f_e <= e_o
// (e_h, e_o: the largest deviations over the three vertices, computed at renewal in double from
// the rounded coefficients: the bound holds however ill-conditioned the triangle). For w = q - x:
// (n.w)^2 + (m_e.w)^2 <= (1 + 5e-7) |w|^2, n.w is at least |n.(q - p) - d| - e_h in size and
// m_e.w at least m_e.(q - p) - f_e - e_o. Those two values are evaluated in float from the float
// q - p (|q - p| <= r), with an error below 1e-6 (r + |d|) (resp. |f_e|), added to the slacks
// sh, so. The squared bound is multiplied by 0.999998 (the Gram factor and the float rounding of
// the squares) and compared with the running best (sqrt(d2) + tol)^2 rounded up to float: a
// triangle is pruned only when its exact distance is strictly above the best's.
#include "methods/ebp_octree/core/certificate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "methods/ebp_octree/core/float_coords.hpp"

namespace ebp {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

inline double max_abs(const Vec3d& v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

/// A float >= x (x >= 0): rounding to float loses less than 1e-6 of x.
inline float float_above(double x) { return float(x * (1 + 1e-6)); }

inline Vec3d rounded(const Vec3d& v) { return {double(float(v.x)), double(float(v.y)), double(float(v.z))}; }
}  // namespace

double certificate_tol(const Vec3d& p, const Vec3d& root_lo, double root_size) {
  return 4e-12 * (max_abs(p) + max_abs(root_lo) + root_size);
}

DistanceCertificate::DistanceCertificate() : kernel_(best_scan_kernel()) {}

void DistanceCertificate::begin(const Vec3d& p, double r_max, double r_floor, double tol) {
  valid_ = false;
  centre_ = p;
  r_max_ = r_max;
  r_floor_ = std::min(r_floor, r_max);
  tol_ = tol;
  prune_ = best_ = kInf;
  heap_.clear();
  members_.clear();
  win_ = CertifiedHit{};
  win_.d2 = kInf;
}

void DistanceCertificate::update_prune() {
  // best + min(2 r_max, max(d_(K+1) - best, 2 r_floor)): non-increasing as best and d_(K+1)
  // decrease, so everything within the final radius was offered (finish() relies on it).
  const double dk = heap_.size() == rule_.nearest + 1 ? heap_.front() : kInf;
  const double extra = std::min(2 * r_max_, std::max(dk - best_, 2 * r_floor_));
  prune_ = std::min(prune_, best_ + extra + 6 * tol_);
}

double DistanceCertificate::offer(double d2, const Vec3d& closest, std::uint64_t key, const LeafTri& t,
                                  const TriangleSite& site) {
  const double d = std::sqrt(d2);
  if (d > prune_) return prune_;
  Member m;
  std::copy(t.a, t.a + 3, m.a);
  std::copy(t.b, t.b + 3, m.b);
  std::copy(t.c, t.c + 3, m.c);
  m.key = key;
  m.site = site;
  m.d = d;
  members_.push_back(m);
  if (better(d2, key, win_.d2, win_.key)) {
    win_.d2 = d2;
    win_.closest = closest;
    win_.key = key;
    win_.site = site;
    win_index_ = std::uint32_t(members_.size() - 1);
  }
  if (heap_.size() < rule_.nearest + 1) {
    heap_.push_back(d);
    std::push_heap(heap_.begin(), heap_.end());
  } else if (d < heap_.front()) {
    std::pop_heap(heap_.begin(), heap_.end());
    heap_.back() = d;
    std::push_heap(heap_.begin(), heap_.end());
  }
  best_ = std::min(best_, d);
  update_prune();
  return prune_;
}

bool DistanceCertificate::finish(CertifiedHit* winner) {
  if (members_.empty()) return false;
  const double best = std::sqrt(win_.d2);
  const double dk = heap_.size() == rule_.nearest + 1 ? heap_.front() : kInf;
  double r = std::max(r_floor_, 0.5 * (dk - best - 6 * tol_));
  r = std::max(0.0, std::min(r_max_, r));
  const double keep = best + 2 * r + 5 * tol_;  // <= the prune radius (certificate.hpp)
  // S: the members within `keep`, the winner first (it is the scan's first running best).
  std::swap(members_[0], members_[win_index_]);
  std::size_t n = 1;
  for (std::size_t i = 1; i < members_.size(); ++i)
    if (members_[i].d <= keep) members_[n++] = members_[i];
  offered_ = std::uint32_t(members_.size());
  members_.resize(n);
  current_ = 0;
  r_ = r;
  r2_ = r * r;
  pack(r);
  valid_ = true;
  win_.normal = members_[0].normal;
  *winner = win_;
  return true;
}

const DistanceCertificate::Directions& DistanceCertificate::directions(const Member& m) {
  if (directions_.empty()) directions_.resize(kDirectionSlots);
  Directions& e = directions_[m.key % kDirectionSlots];
  if (e.key == m.key) return e;
  e.key = m.key;
  const Vec3d a = to_d(m.a), b = to_d(m.b), c = to_d(m.c);
  e.normal = bvhbench::triangle_normal(a, b, c);  // the answer's, exactly as the search computes it
  e.plane = false;
  const Vec3d nd = cross(b - a, c - a);
  const double len = norm(nd);
  if (!(len > 0) || !std::isfinite(len)) return e;  // no plane: bound 0, always tested exactly
  e.plane = true;
  const Vec3d nrm = nd / len;
  const Vec3d nf = rounded(nrm);
  e.n[0] = float(nf.x), e.n[1] = float(nf.y), e.n[2] = float(nf.z);
  const Vec3d V[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const Vec3d& v0 = V[k];
    const Vec3d md = cross(V[(k + 1) % 3] - v0, nrm);
    const double ml = norm(md);
    Vec3d mf{0, 0, 0};
    if (ml > 0 && std::isfinite(ml)) mf = rounded(dot(md, V[(k + 2) % 3] - v0) > 0 ? md / (-ml) : md / ml);
    e.m[k][0] = float(mf.x), e.m[k][1] = float(mf.y), e.m[k][2] = float(mf.z);
  }
  return e;
}

void DistanceCertificate::pack(double r) {
  const std::size_t n = members_.size(), blocks = (n + kScanLanes - 1) / kScanLanes;
  pack_.assign(blocks * kScanRows * kScanLanes, 0.0f);
  masks_.assign(blocks, 0);
  for (std::size_t i = 0; i < blocks * kScanLanes; ++i) {
    float* lane = pack_.data() + (i / kScanLanes) * kScanRows * kScanLanes + i % kScanLanes;
    auto put = [&](unsigned row, double v) { lane[row * kScanLanes] = float(v); };
    if (i >= n) {  // padding: an infinite bound
      put(16, -kInf);
      put(17, -kInf);
      continue;
    }
    Member& m = members_[i];
    const Directions& dir = directions(m);
    m.normal = dir.normal;
    if (!dir.plane) continue;  // all zero: bound 0, always tested exactly
    // The offsets and the deviations of the rounded planes, relative to the centre.
    const Vec3d V[3] = {to_d(m.a) - centre_, to_d(m.b) - centre_, to_d(m.c) - centre_};
    double vmax = 0;
    for (const Vec3d& v : V) vmax = std::max(vmax, max_abs(v));
    const Vec3d nf = to_d(dir.n);
    const double d = double(float(dot(nf, V[0])));
    double eh = 0;
    for (const Vec3d& v : V) eh = std::max(eh, std::fabs(dot(nf, v) - d));
    put(0, nf.x);
    put(1, nf.y);
    put(2, nf.z);
    put(3, d);
    double so = 0, fmax = 0;
    for (int e = 0; e < 3; ++e) {
      const Vec3d mf = to_d(dir.m[e]);
      const double f = double(float(dot(mf, V[e])));
      double eo = 0;
      for (const Vec3d& v : V) eo = std::max(eo, dot(mf, v) - f);
      so = std::max(so, eo);
      fmax = std::max(fmax, std::fabs(f));
      put(4 + 4 * unsigned(e), mf.x);
      put(5 + 4 * unsigned(e), mf.y);
      put(6 + 4 * unsigned(e), mf.z);
      put(7 + 4 * unsigned(e), f);
    }
    // The double evaluation of the deviations (1e-12 of the magnitudes) and the float
    // evaluation at q (1e-6 (r + |offset|)), rounded up to float.
    const double guard = 1e-12 * (vmax + std::fabs(d) + fmax);
    lane[16 * kScanLanes] = float_above(eh + guard + 1e-6 * (r + std::fabs(d)));
    lane[17 * kScanLanes] = float_above(so + guard + 1e-6 * (r + fmax));
  }
}

bool DistanceCertificate::covers(const Vec3d& q) const { return valid_ && squared_norm(q - centre_) <= r2_; }

void DistanceCertificate::exact(std::uint32_t i, const Vec3d& q, CertifiedHit* hit, QueryCounters& c) const {
  const Member& m = members_[i];
  ++c.triangles_tested;
  hit->closest = bvhbench::closest_point_on_triangle(q, to_d(m.a), to_d(m.b), to_d(m.c));
  hit->d2 = squared_norm(hit->closest - q);
  hit->key = m.key;
  hit->site = m.site;
}

CertifiedHit DistanceCertificate::serve(const Vec3d& q, QueryCounters& c) {
  CertifiedHit h;
  exact(current_, q, &h, c);
  h.runner2 = kInf;
  std::uint32_t win = current_;
  const std::uint32_t n = std::uint32_t(members_.size());
  if (n > 1) {
    const double u = std::sqrt(h.d2) + tol_;
    const Vec3d ql = q - centre_;
    const float qf[3] = {float(ql.x), float(ql.y), float(ql.z)};
    const std::uint32_t blocks = std::uint32_t(masks_.size());
    scan_lower_bounds(kernel_, pack_.data(), blocks, qf, float_above(u * u), masks_.data());
    c.planes_tested += n;
    for (std::uint32_t j = 0; j < blocks; ++j)
      for (unsigned bits = masks_[j]; bits; bits &= bits - 1) {
        const std::uint32_t i = j * kScanLanes + unsigned(__builtin_ctz(bits));
        if (i == current_ || i >= n) continue;
        CertifiedHit x;
        exact(i, q, &x, c);
        if (better(x.d2, x.key, h.d2, h.key)) {
          x.runner2 = std::min(h.runner2, h.d2);
          h = x;
          win = i;
        } else {
          h.runner2 = std::min(h.runner2, x.d2);
        }
      }
  }
  current_ = win;
  h.normal = members_[win].normal;
  return h;
}

Vec3d CertifiedPath::ahead(const Vec3d& q) const {
  Vec3d dir(0, 0, 0);  // the last step's direction (unit, or zero)
  if (nsteps_ > 0) {
    const Vec3d& m = moves_[(next_ + kStepWindow - 1) % kStepWindow];
    const double len = norm(m);
    if (len > 0) dir = m / len;
  }
  const Vec3d c = q + dir * (cert.rule().ahead * last_r_);
  return std::isfinite(c.x + c.y + c.z) ? c : q;
}

void CertifiedPath::close_account() {
  if (!account_open_) return;
  account_open_ = false;
  if (account_queries_ > 0) {
    const double x = account_work_ / double(account_queries_);
    // A moving average over about four certificates: one lost at a jump of the path must not
    // start a streak where certificates win (measured: halving it cost 12 % on the cow's path).
    cert_work_ = cert_work_ < 0 || fresh_ ? x : cert_work_ + (x - cert_work_) / 4;
  }
  fresh_ = false;
  account_work_ = 0;
  account_queries_ = 0;
}

bool CertifiedPath::prefer_plain() {
  close_account();
  if (!adaptive_) return false;
  if (plain_left_ > 0) {
    if (--plain_left_ == 0) trial_ = true;
    return true;
  }
  if (probe_left_ > 0) {
    --probe_left_;
    return true;
  }
  if (trial_) {  // after a streak: one certificate, whose cost replaces the estimate
    trial_ = false;
    fresh_ = true;
    return false;
  }
  if (cert_work_ >= 0 && (plain_work_ < 0 || certs_since_plain_ >= kProbeEvery)) {
    // the plain estimate is missing or old: measure it (this query is the probe's first)
    cert.clear();
    probe_left_ = kProbe - 1;
    probe_n_ = 0;
    probe_sum_ = 0;
    certs_since_plain_ = 0;
    return true;
  }
  // A margin (kPlainMargin): the estimates are averages of noisy samples, and on the small models
  // certificates that were about as dear as plain searches still won over the next stretch.
  if (cert_work_ >= 0 && plain_work_ >= 0 && cert_work_ > kPlainMargin * plain_work_) {
    cert.clear();
    plain_left_ = streak_ - 1;  // this query is the streak's first
    if (plain_left_ == 0) trial_ = true;
    streak_ = std::min(2 * streak_, kPlainStreakMax);
    return true;
  }
  streak_ = kPlainStreakMin;  // certificates pay here: a later losing stretch starts short
  return false;
}

void CertifiedPath::plain_answered(double work) {
  certs_since_plain_ = 0;
  if (probe_n_ < kProbe) {  // a probe's search: the estimate is its mean
    probe_sum_ += work;
    ++probe_n_;
    plain_work_ = probe_sum_ / double(probe_n_);
    return;
  }
  plain_work_ = plain_work_ < 0 ? work : plain_work_ + (work - plain_work_) / 8;
}

void CertifiedPath::reset() {
  have_prev_ = false;
  last_r_ = 0;
  plain_work_ = cert_work_ = -1;
  account_work_ = 0;
  account_queries_ = 0;
  account_open_ = trial_ = fresh_ = false;
  plain_left_ = 0;
  streak_ = kPlainStreakMin;
  certs_since_plain_ = probe_left_ = 0;
  probe_n_ = kProbe;
  probe_sum_ = 0;
  nsteps_ = next_ = 0;
  sign_ok_ = false;
  cert.clear();
}

void CertifiedPath::step_to(const Vec3d& q) {
  if (have_prev_) {
    moves_[next_] = q - prev_;
    next_ = (next_ + 1) % kStepWindow;
    nsteps_ = std::min(nsteps_ + 1, kStepWindow);
  }
  have_prev_ = true;
  prev_ = q;
}

double CertifiedPath::mean_step() const {
  if (nsteps_ == 0) return 0;
  double s = 0;
  for (unsigned i = 0; i < nsteps_; ++i) s += norm(moves_[i]);
  return s / double(nsteps_);
}

bool CertifiedPath::jumped(double leaf_cell) const {
  if (nsteps_ == 0) return false;
  // the last step q - q_prev, measured as step_length(q, q_prev) measures it
  const double last = max_abs(moves_[(next_ + kStepWindow - 1) % kStepWindow]);
  return std::max(last, mean_step()) > leaf_cell;
}

bool CertifiedPath::radii(double* r_max, double* r_floor) const {
  if (nsteps_ == 0) return false;
  const double step = mean_step();
  if (!std::isfinite(step)) return false;
  *r_max = cert.rule().step_factor * step;
  // Where the K-nearest term set the last radius (small triangles), start the collection from
  // a multiple of it: the relaxed search then tests the triangles near p, not the whole cap of
  // 16 steps, before it has K + 1 of them (the radius grows back by this factor per renewal).
  if (last_r_ > 0) *r_max = std::min(*r_max, cert.rule().growth * last_r_);
  *r_floor = std::min(cert.rule().floor_factor * step, *r_max);
  return true;
}

bool CertifiedPath::sign_chained(const Vec3d& q, double distance, double tol, bool* inside) const {
  if (!sign_ok_) return false;
  const double lim = (sign_best_ - 2 * tol) + std::max(0.0, distance - 2 * tol);
  if (!(lim > 0) || !(squared_norm(q - sign_p_) < lim * lim)) return false;
  *inside = sign_in_;
  return true;
}

void CertifiedPath::answered(const Vec3d& q, double distance, bool inside) {
  sign_ok_ = true;
  sign_p_ = q;
  sign_best_ = distance;
  sign_in_ = inside;
}

}  // namespace ebp
