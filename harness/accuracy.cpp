#include "accuracy.hpp"

#include <algorithm>
#include <cmath>

#include "errors.hpp"
#include "npy.hpp"

namespace bvhbench {

using json = nlohmann::json;

void Answers::resize(QueryType t, std::size_t n) {
  type = t;
  if (t == QueryType::inside) {
    inside.assign(n, 0);
  } else {
    distance.assign(n, 0.0);
    closest.assign(n, Vec3d{});
    normal.assign(n, Vec3d{});
    triangle.assign(n, -1);
  }
}

void Answers::write_npz(const std::string& path) const {
  std::map<std::string, NpyArray> a;
  if (type == QueryType::inside) {
    a["inside"] = NpyArray::b1(inside);
  } else {
    a["distance"] = NpyArray::f8(distance);
    a["closest"] = NpyArray::f8_n3(closest);
    a["normal"] = NpyArray::f8_n3(normal);
    a["triangle"] = NpyArray::i8(triangle);
  }
  bvhbench::write_npz(path, a);
}

namespace {

json error_stats(std::vector<double> v) {
  if (v.empty()) return {{"max", nullptr}, {"p99", nullptr}, {"mean", nullptr}};
  double sum = 0;
  for (double x : v) sum += x;
  std::sort(v.begin(), v.end());
  std::size_t i99 = std::min(v.size() - 1, std::size_t(std::ceil(0.99 * double(v.size()))) - 1);
  return {{"max", v.back()}, {"p99", v[i99]}, {"mean", sum / double(v.size())}};
}

const NpyArray& need(const std::map<std::string, NpyArray>& t, const std::string& path,
                     const std::string& key, const std::string& dtype, std::size_t n,
                     std::size_t cols) {
  auto it = t.find(key);
  if (it == t.end()) throw file_error(path, "oracle has no '" + key + "' array");
  const NpyArray& a = it->second;
  if (a.dtype != dtype) throw file_error(path, "oracle '" + key + "' has dtype " + a.dtype + ", expected " + dtype);
  std::size_t want = n * cols;
  if (a.size() != want)
    throw file_error(path, "oracle '" + key + "' has " + std::to_string(a.size()) + " values, expected " +
                               std::to_string(want) + " (does it belong to this query set?)");
  return a;
}

}  // namespace

json compute_accuracy(const Answers& ans, const std::string& truth_path, double diagonal) {
  auto t = read_npz(truth_path);
  const std::size_t n = ans.type == QueryType::inside ? ans.inside.size() : ans.distance.size();
  const double near_thr = 1e-6 * diagonal;
  json acc;
  acc["truth"] = truth_path;
  acc["near_surface_threshold"] = near_thr;
  std::string definition = "unknown";
  auto d = t.find("definition");
  if (d != t.end() && d->second.dtype.size() > 2 && d->second.dtype[1] == 'U') {
    // NumPy unicode: UTF-32LE code units; our definitions are ASCII.
    definition.clear();
    for (std::size_t i = 0; i + 3 < d->second.data.size(); i += 4) {
      char c = d->second.data[i];
      if (c) definition += c;
    }
  }
  acc["definition"] = definition;

  const NpyArray& tdist = need(t, truth_path, "distance", "<f8", n, 1);
  const double* td = tdist.as<double>();

  if (ans.type == QueryType::inside) {
    const NpyArray& tin = need(t, truth_path, "inside", "|b1", n, 1);
    const std::uint8_t* ti = tin.as<std::uint8_t>();
    std::size_t wrong = 0, near = 0, wrong_near = 0;
    for (std::size_t i = 0; i < n; ++i) {
      bool is_near = std::abs(td[i]) < near_thr;
      bool bad = (ans.inside[i] != 0) != (ti[i] != 0);
      near += is_near;
      wrong += bad;
      wrong_near += bad && is_near;
    }
    std::size_t n_far = n - near;
    acc["inside"] = {{"wrong", wrong},
                     {"rate", n ? double(wrong) / double(n) : 0.0},
                     {"near_surface", near},
                     {"wrong_near_surface", wrong_near},
                     {"wrong_far", wrong - wrong_near},
                     {"n_far", n_far},
                     {"rate_far", n_far ? double(wrong - wrong_near) / double(n_far) : 0.0}};
    acc["distance"] = nullptr;
  } else {
    const NpyArray& tin = need(t, truth_path, "inside", "|b1", n, 1);
    const std::uint8_t* ti = tin.as<std::uint8_t>();
    const std::int64_t* tt = need(t, truth_path, "triangle", "<i8", n, 1).as<std::int64_t>();
    const std::int64_t* ties = nullptr;
    if (t.count("tie_count")) ties = need(t, truth_path, "tie_count", "<i8", n, 1).as<std::int64_t>();
    std::vector<double> abs_err(n), rel_err(n), angle;
    std::size_t sign_wrong = 0, tri_same = 0, tri_known = 0, tri_tied = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double truth_signed = ti[i] ? -td[i] : td[i];
      double e = std::abs(ans.distance[i] - truth_signed);
      // A sign flip on a point closer than the threshold is not counted as an error.
      if (std::abs(td[i]) < near_thr) e = std::abs(std::abs(ans.distance[i]) - td[i]);
      else if ((ans.distance[i] < 0) != (truth_signed < 0)) ++sign_wrong;
      abs_err[i] = e;
      rel_err[i] = diagonal > 0 ? e / diagonal : e;
      if (ans.triangle[i] >= 0) {
        if (ties && ties[i] > 1) {
          ++tri_tied;
        } else {
          ++tri_known;
          tri_same += ans.triangle[i] == tt[i];
        }
      }
    }
    // Normal angle error: against the oracle's triangle normal when the oracle provides normals.
    if (t.count("normal")) {
      const double* tn = need(t, truth_path, "normal", "<f8", n, 3).as<double>();
      for (std::size_t i = 0; i < n; ++i) {
        if (ties && ties[i] > 1) continue;  // the contact normal is ambiguous on a shared edge
        Vec3d a = normalized(ans.normal[i]);
        Vec3d b{tn[3 * i], tn[3 * i + 1], tn[3 * i + 2]};
        if (squared_norm(a) == 0 || squared_norm(b) == 0) continue;
        double c = std::clamp(dot(a, normalized(b)), -1.0, 1.0);
        angle.push_back(std::acos(c) * 57.29577951308232);
      }
    }
    acc["inside"] = nullptr;
    acc["distance"] = {{"abs_error", error_stats(abs_err)},
                       {"rel_error", error_stats(rel_err)},
                       {"normal_angle_deg", error_stats(angle)},
                       {"sign_wrong", sign_wrong},
                       {"triangle_agreement", tri_known ? json(double(tri_same) / double(tri_known)) : json(nullptr)},
                       {"triangle_compared", tri_known},
                       {"triangle_tied", tri_tied}};
  }
  return acc;
}

}  // namespace bvhbench
