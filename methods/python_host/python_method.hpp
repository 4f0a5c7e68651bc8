#pragma once
/// A method written in Python (methods/<name>/method.py), behind the C++ Method interface.
///
/// The module's class `Method(**parameters)` answers:
///   build(V, F)      V (nV, 3) float64, F (nF, 3) int64: the mesh, once;
///   inside(P)        P (N, 3) float64, read-only -> (N,) bool;
///   distance(P)      -> (signed (N,), closest (N, 3), normal (N, 3), triangle (N,) int64, -1 unknown);
/// and may offer inside_one(p) -> bool and distance_one(p) -> (signed, closest, normal, triangle)
/// with p a tuple of 3 floats (the per-query path; without them a query is inside(P) of one row),
/// structure_bytes(), counters() -> {name: total}, reset_counters(), reset_path(),
/// supports(query) -> bool and info() -> dict.
///
/// With `batch=true` the harness calls inside(P) / distance(P) once per pass on the whole query
/// set (it is a BatchAnswers, harness/core/batch_answers.hpp); otherwise once per query, so that a query's latency
/// includes the interpreter's cost, as it would for a Python caller. Every answer is checked
/// (type, shape, finite): a wrong one throws, so the job ends with status `error` and a message
/// naming the method, the call and the problem.
#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "harness/core/batch_answers.hpp"
#include "harness/core/method.hpp"

namespace bvhbench {

struct PythonMethodDeclaration {
  std::string name;    ///< the folder's name
  std::string folder;  ///< holds method.py
  Capabilities caps;
};

class PythonMethod final : public Method, public BatchAnswers {
 public:
  /// Imports the module and makes its Method from `params` (every declared one, validated).
  /// Throws UnsupportedError when the module raises NotImplementedError, std::runtime_error
  /// naming the method for any other Python exception.
  PythonMethod(PythonMethodDeclaration decl, const Params& params);
  ~PythonMethod() override;

  void build(const Mesh& mesh, const BuildContext& ctx) override;
  bool inside(const Vec3d& p) override;
  DistanceResult distance(const Vec3d& p) override;
  bool answers_in_batches() const override { return batch_; }
  void inside_batch(const std::vector<Vec3d>& points, std::vector<std::uint8_t>& inside) override;
  void distance_batch(const std::vector<Vec3d>& points, std::vector<DistanceResult>& out) override;
  bool supports(QueryType q) const override;
  void reset_path() override;
  std::size_t structure_bytes() const override;
  std::vector<Counter> counters() const override;
  void reset_counters() override;
  nlohmann::json info() const override;

 private:
  /// Runs `f` with the GIL held, turning a Python exception into the harness's errors.
  template <class F>
  auto call(const char* what, F&& f) const;
  pybind11::object points_array(const std::vector<Vec3d>& points) const;

  PythonMethodDeclaration decl_;
  bool batch_ = false;
  pybind11::object instance_;      // the module's Method
  pybind11::object inside_one_;    // bound methods, or None
  pybind11::object distance_one_;
};

}  // namespace bvhbench
