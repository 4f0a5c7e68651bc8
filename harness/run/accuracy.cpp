#include "harness/run/accuracy.hpp"

#include <algorithm>
#include <cmath>

#include "harness/io/npz.hpp"
#include "harness/run/accuracy_truths.hpp"
#include "harness/util/errors.hpp"

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

void Answers::keep_first(std::size_t n) {
  if (inside.size() > n) inside.resize(n);
  if (distance.size() > n) {
    distance.resize(n);
    closest.resize(n);
    normal.resize(n);
    triangle.resize(n);
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

/// max / p99 / mean of finite values (null when there are none).
json error_stats(std::vector<double> v) {
  if (v.empty()) return {{"max", nullptr}, {"p99", nullptr}, {"mean", nullptr}};
  double sum = 0;
  for (double x : v) sum += x;
  std::sort(v.begin(), v.end());
  std::size_t i99 = std::min(v.size() - 1, std::size_t(std::ceil(0.99 * double(v.size()))) - 1);
  return {{"max", v.back()}, {"p99", v[i99]}, {"mean", sum / double(v.size())}};
}


bool finite(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// Examples of definition-dependent points recorded per job (the first ones in query order).
constexpr std::size_t kDependentExamples = 5;

/// The judging of a method's inside against its own definition (inside_definition.hpp), shared
/// by inside jobs (the answers) and distance jobs (the answers' signs).
struct Judge {
  const InsideTruths& truths;
  const InsideDefinition& definition;
  const std::vector<Vec3d>& points;
  std::size_t n;

  /// What the method's own definition says at query i (the oracle's default where the mesh
  /// does not define it).
  bool truth(std::size_t i) const { return truths.inside(definition, i); }

  /// The fields that say what was judged against what, and whether the mesh is within the
  /// method's contract.
  void describe(json& acc) const {
    acc["definitions"] = truths.defined();
    acc["judged_against"] = truths.judged_against(definition);
    const std::string problem = truths.contract_problem(definition.contract);
    acc["within_contract"] = definition.contract == InputContract::undeclared ? json(nullptr) : json(problem.empty());
    acc["contract_problem"] = problem.empty() ? json(nullptr) : json(problem);
  }

  /// acc["definition_dependent"] (the points where the mesh's definitions disagree: how many, how
  /// many of them the method got wrong under its own, the first few with what each definition
  /// says) and acc["by_definition"] (the method's wrong answers under each definition defined on
  /// this mesh). `answered(i)`: the method's inside at query i; `judged(i)`: whether query i
  /// counts (a distance's sign does not near the surface).
  template <class Answered, class Judged>
  void definitions(json& acc, Answered answered, Judged judged) const {
    std::map<std::string, std::size_t> wrong_under;
    for (const std::string& d : truths.defined()) wrong_under[d] = 0;
    std::size_t dependent = 0, wrong_dependent = 0;
    json examples = json::array();
    for (std::size_t i = 0; i < n; ++i) {
      if (!judged(i)) continue;
      const bool a = answered(i);
      const auto says = truths.says(i);
      for (const auto& [d, s] : says) wrong_under[d] += s != a;
      if (!truths.dependent(i)) continue;
      ++dependent;
      wrong_dependent += a != truth(i);
      if (examples.size() < kDependentExamples) examples.push_back(example(i, a, says));
    }
    acc["definition_dependent"] = {{"count", dependent}, {"wrong", wrong_dependent}, {"examples", examples}};
    acc["by_definition"] = wrong_under;
  }

  json example(std::size_t i, bool answered, const std::map<std::string, bool>& says) const {
    json e = {{"index", i}, {"winding", truths.winding(i)}, {"says", says}, {"answered", answered}};
    if (i < points.size()) e["point"] = {points[i].x, points[i].y, points[i].z};
    return e;
  }
};

/// Throws when the oracle file names another query set or mesh than the job's.
void check_oracle_belongs(const std::map<std::string, NpyArray>& t, const std::string& truth_path,
                          const std::string& queries_sha256, const std::string& mesh_sha256) {
  const std::string truth_qsha = oracle_string(t, "queries_sha256");
  if (!queries_sha256.empty() && !truth_qsha.empty() && truth_qsha != queries_sha256)
    throw file_error(truth_path, "oracle was computed for another query set (queries_sha256 " +
                                     truth_qsha.substr(0, 16) + "..., this query set is " +
                                     queries_sha256.substr(0, 16) + "...); recompute it with bvhbench truth");
  const std::string truth_msha = oracle_string(t, "mesh_sha256");
  if (!mesh_sha256.empty() && !truth_msha.empty() && truth_msha != mesh_sha256)
    throw file_error(truth_path, "oracle was computed for another mesh (mesh_sha256 " + truth_msha.substr(0, 16) +
                                     "..., this mesh is " + mesh_sha256.substr(0, 16) +
                                     "...); recompute it with bvhbench truth");
}

/// acc["inside"]: the wrong answers under the method's own definition (judge), near and far
/// from the surface, and, on an open mesh, at ambiguous points (|w| far from both 0 and 1: the
/// threshold at 1/2 decides them, and a method may reasonably decide otherwise).
void inside_block(json& acc, const Answers& ans, const Judge& judge, const double* td, double near_thr) {
  const std::size_t n = judge.n;
  std::size_t near = 0, wrong = 0, wrong_near = 0, ambiguous = 0, wrong_ambiguous = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool is_near = std::abs(td[i]) < near_thr;
    const bool amb = judge.truths.ambiguous(i);
    const bool bad = (ans.inside[i] != 0) != judge.truth(i);
    near += is_near;
    ambiguous += amb;
    wrong += bad;
    wrong_near += bad && is_near;
    wrong_ambiguous += bad && amb;
  }
  const std::size_t n_far = n - near;
  acc["inside"] = {{"wrong", wrong},
                   {"rate", n ? double(wrong) / double(n) : 0.0},
                   {"near_surface", near},
                   {"wrong_near_surface", wrong_near},
                   {"wrong_far", wrong - wrong_near},
                   {"n_far", n_far},
                   {"rate_far", n_far ? double(wrong - wrong_near) / double(n_far) : 0.0},
                   {"ambiguous", ambiguous},
                   {"wrong_ambiguous", wrong_ambiguous}};
  judge.definitions(acc, [&](std::size_t i) { return ans.inside[i] != 0; }, [](std::size_t) { return true; });
  acc["distance"] = nullptr;
}

/// acc["distance"]: errors of the signed distance (its sign judged under the method's own
/// definition), the closest point, the contact normal and the closest triangle.
void distance_block(json& acc, const Answers& ans, const Judge& judge, const std::map<std::string, NpyArray>& t,
                    const std::string& truth_path, const double* td, double near_thr, double diagonal) {
  const std::size_t n = judge.n;
  std::size_t near = 0;
  for (std::size_t i = 0; i < n; ++i) near += std::abs(td[i]) < near_thr;
  const std::int64_t* tt = oracle_array(t, truth_path, "triangle", "<i8", n, 1).as<std::int64_t>();
  const std::int64_t* ties = t.count("tie_count") ? oracle_array(t, truth_path, "tie_count", "<i8", n, 1).as<std::int64_t>() : nullptr;
  std::size_t max_tied = 0;
  const std::int64_t* tied = nullptr;
  if (t.count("tied_triangles") && t.at("tied_triangles").shape.size() == 2) {
    max_tied = t.at("tied_triangles").shape[1];
    tied = oracle_array(t, truth_path, "tied_triangles", "<i8", n, max_tied).as<std::int64_t>();
  }
  const double* tc = t.count("closest") ? oracle_array(t, truth_path, "closest", "<f8", n, 3).as<double>() : nullptr;
  const double* tn = t.count("normal") ? oracle_array(t, truth_path, "normal", "<f8", n, 3).as<double>() : nullptr;

  std::vector<double> abs_err, rel_err, angle, closest_err;
  abs_err.reserve(n);
  rel_err.reserve(n);
  std::size_t sign_wrong = 0, non_finite = 0, tri_same = 0, tri_compared = 0, tri_tied = 0, tri_unknown = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = ans.distance[i];
    if (!std::isfinite(a)) {  // NaN / inf: counted, kept out of the statistics
      ++non_finite;
      continue;
    }
    const bool is_near = std::abs(td[i]) < near_thr;
    const bool truth_inside = judge.truth(i);
    const double truth_signed = truth_inside ? -td[i] : td[i];
    double e = std::abs(a - truth_signed);
    // Near the surface the sign is ill-defined: compare magnitudes, and count no sign error.
    if (is_near) e = std::abs(std::abs(a) - td[i]);
    else if ((a < 0) != truth_inside) ++sign_wrong;
    abs_err.push_back(e);
    rel_err.push_back(diagonal > 0 ? e / diagonal : e);
    if (tc && finite(ans.closest[i])) {
      Vec3d q{tc[3 * i], tc[3 * i + 1], tc[3 * i + 2]};
      closest_err.push_back(norm(ans.closest[i] - q));
    }
    const std::int64_t tri = ans.triangle[i];
    const std::int64_t nt = ties ? ties[i] : 1;
    if (tri < 0) {
      ++tri_unknown;
    } else if (nt <= 1) {
      ++tri_compared;
      tri_same += tri == tt[i];
    } else if (tied && std::size_t(nt) <= max_tied) {
      // A tie (shared edge or vertex): any of the tied triangles is right.
      ++tri_compared;
      ++tri_tied;
      for (std::size_t k = 0; k < max_tied; ++k) tri_same += tied[i * max_tied + k] == tri;
    } else {
      ++tri_tied;  // more ties than recorded: not compared
    }
    // The contact normal against the closest triangle's face normal, where that is unambiguous.
    if (tn && nt <= 1) {
      Vec3d m = ans.normal[i];
      Vec3d b{tn[3 * i], tn[3 * i + 1], tn[3 * i + 2]};
      if (!finite(m) || squared_norm(m) == 0) {
        angle.push_back(180.0);  // no usable normal: as wrong as it gets
      } else if (squared_norm(b) > 0) {
        double c = std::clamp(dot(normalized(m), normalized(b)), -1.0, 1.0);
        angle.push_back(std::acos(c) * 57.29577951308232);
      }
    }
  }
  acc["inside"] = nullptr;
  acc["distance"] = {{"abs_error", error_stats(abs_err)},
                     {"rel_error", error_stats(rel_err)},
                     {"closest_error", error_stats(closest_err)},
                     {"normal_angle_deg", error_stats(angle)},
                     {"sign_wrong", sign_wrong},
                     {"sign_wrong_rate", n - near ? double(sign_wrong) / double(n - near) : 0.0},
                     {"non_finite", non_finite},
                     {"triangle_agreement", tri_compared ? json(double(tri_same) / double(tri_compared)) : json(nullptr)},
                     {"triangle_compared", tri_compared},
                     {"triangle_tied", tri_tied},
                     {"triangle_unknown", tri_unknown}};
  // A sign is judged away from the surface, for finite answers only.
  judge.definitions(acc, [&](std::size_t i) { return ans.distance[i] < 0; },
                    [&](std::size_t i) { return std::isfinite(ans.distance[i]) && !(std::abs(td[i]) < near_thr); });
}

}  // namespace

json compute_accuracy(const Answers& ans, const std::string& truth_path, double diagonal,
                      const std::string& queries_sha256, const std::string& mesh_sha256,
                      const InsideDefinition& inside, const std::vector<Vec3d>& points) {
  auto t = read_npz(truth_path);
  check_oracle_belongs(t, truth_path, queries_sha256, mesh_sha256);
  const std::size_t n = ans.type == QueryType::inside ? ans.inside.size() : ans.distance.size();
  const double near_thr = 1e-6 * diagonal;
  json acc;
  acc["truth"] = truth_path;
  acc["near_surface_threshold"] = near_thr;
  const std::string definition = oracle_string(t, "definition");
  acc["definition"] = definition.empty() ? "unknown" : definition;

  const double* td = oracle_array(t, truth_path, "distance", "<f8", n, 1).as<double>();
  const InsideTruths truths(t, truth_path, n);
  std::size_t near = 0;
  for (std::size_t i = 0; i < n; ++i) near += std::abs(td[i]) < near_thr;
  acc["near_surface"] = near;
  const Judge judge{truths, inside, points, n};
  judge.describe(acc);
  if (ans.type == QueryType::inside) inside_block(acc, ans, judge, td, near_thr);
  else distance_block(acc, ans, judge, t, truth_path, td, near_thr, diagonal);
  return acc;
}

}  // namespace bvhbench
