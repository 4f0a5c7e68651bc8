#include "python_method.hpp"

#include <Python.h>

#include <cmath>
#include <cstring>
#include <new>
#include <stdexcept>

#include <pybind11/numpy.h>

#include "harness/core/library_versions.hpp"
#include "harness/core/mesh.hpp"
#include "harness/util/errors.hpp"
#include "python_runtime.hpp"

namespace py = pybind11;

namespace bvhbench {

static_assert(sizeof(Vec3d) == 3 * sizeof(double), "Vec3d must be 3 packed doubles: numpy views them as (N, 3)");

namespace {

std::string point_text(const Vec3d& p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

/// A finite float from a Python number (float, int, numpy scalar), or throws naming `what`.
double finite_number(PyObject* o, const std::string& what) {
  double v = PyFloat_AsDouble(o);
  if (v == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    throw std::runtime_error(what + ": not a number (" + Py_TYPE(o)->tp_name + ")");
  }
  if (!std::isfinite(v)) throw std::runtime_error(what + ": " + std::to_string(v) + " is not finite");
  return v;
}

/// A 3-vector from a sequence of 3 numbers (tuple, list, numpy (3,)).
Vec3d finite_vec3(PyObject* o, const std::string& what) {
  if (!PySequence_Check(o) || PySequence_Size(o) != 3) {
    PyErr_Clear();
    throw std::runtime_error(what + ": expected 3 numbers, got " + Py_TYPE(o)->tp_name);
  }
  double v[3];
  for (int i = 0; i < 3; ++i) {
    py::object item = py::reinterpret_steal<py::object>(PySequence_GetItem(o, i));
    if (!item) throw py::error_already_set();
    v[i] = finite_number(item.ptr(), what);
  }
  return {v[0], v[1], v[2]};
}

/// A bool from a Python bool, int or numpy scalar of kind b/i/u, never from None or a list.
bool truth(const py::object& r, const std::string& what) {
  if (PyBool_Check(r.ptr()) || PyLong_Check(r.ptr())) return PyObject_IsTrue(r.ptr()) == 1;
  if (py::hasattr(r, "dtype") && py::hasattr(r, "size") && r.attr("size").cast<long>() == 1) {
    const std::string kind = r.attr("dtype").attr("kind").cast<std::string>();
    if (kind == "b" || kind == "i" || kind == "u") return PyObject_IsTrue(r.attr("item")().ptr()) == 1;
  }
  throw std::runtime_error(what + ": expected a bool, got " + Py_TYPE(r.ptr())->tp_name);
}

}  // namespace

template <class F>
auto PythonMethod::call(const char* what, F&& f) const {
  py::gil_scoped_acquire gil;
  try {
    return f();
  } catch (py::error_already_set& e) {
    const bool unsupported = e.matches(PyExc_NotImplementedError);
    const bool memory = e.matches(PyExc_MemoryError);
    const std::string text = decl_.name + ": " + what + ": " + python_error_text(e);
    if (memory) throw std::bad_alloc();
    if (unsupported) throw UnsupportedError(text);
    throw std::runtime_error(text);
  } catch (py::cast_error& e) {
    throw std::runtime_error(decl_.name + ": " + what + ": " + e.what());
  }
}

PythonMethod::PythonMethod(PythonMethodDeclaration decl, const Params& params) : decl_(std::move(decl)) {
  batch_ = params.get_bool("batch");
  const PythonRuntime& rt = python_runtime();
  if (!rt.ok) throw std::runtime_error(decl_.name + ": " + rt.problem);
  call("import and create", [&] {
    // Typed here, from the declaration: the method gets int, float, bool or str, never a text to parse.
    py::dict values;
    for (const auto& [k, text] : params.values()) {
      if (k == "batch") continue;
      const ParamValue& v = params.value(k);
      switch (v.type) {
        case ParamType::integer: values[py::str(k)] = py::int_(v.integer); break;
        case ParamType::real: values[py::str(k)] = py::float_(v.real); break;
        case ParamType::boolean: values[py::str(k)] = py::bool_(v.boolean); break;
        case ParamType::text:
        case ParamType::choice: values[py::str(k)] = py::str(v.text); break;
      }
    }
    py::tuple made = rt.host.attr("create")(decl_.folder, values);
    instance_ = made[0];
    for (auto item : made[1].cast<py::dict>())
      note_library_version(item.first.cast<std::string>(), item.second.cast<std::string>());
    note_library_version("python", rt.version);
    inside_one_ = py::getattr(instance_, "inside_one", py::none());
    distance_one_ = py::getattr(instance_, "distance_one", py::none());
    return 0;
  });
}

PythonMethod::~PythonMethod() {
  // The objects must be released with the GIL held, so here rather than by the members' destructors.
  py::gil_scoped_acquire gil;
  instance_ = py::object();
  inside_one_ = py::object();
  distance_one_ = py::object();
}

void PythonMethod::build(const Mesh& mesh, const BuildContext&) {
  // The host's guard for every Python method: the libraries have no answer for no triangles.
  if (mesh.triangles.empty()) throw InputError(decl_.name + ": the mesh has no triangles");
  call("build", [&] {
    const py::ssize_t nv = py::ssize_t(mesh.vertices.size()), nf = py::ssize_t(mesh.triangles.size());
    py::array_t<double> V({nv, py::ssize_t(3)});
    if (nv) std::memcpy(V.mutable_data(), mesh.vertices.data(), std::size_t(nv) * sizeof(Vec3d));
    py::array_t<std::int64_t> F({nf, py::ssize_t(3)});
    auto f = F.mutable_unchecked<2>();
    for (py::ssize_t t = 0; t < nf; ++t)
      for (int c = 0; c < 3; ++c) f(t, c) = mesh.triangles[std::size_t(t)][std::size_t(c)];
    instance_.attr("build")(V, F);
    return 0;
  });
}

py::object PythonMethod::points_array(const std::vector<Vec3d>& points) const {
  // A read-only view of the harness's points, not a copy: a batch call costs what the method does.
  const py::ssize_t n = py::ssize_t(points.size());
  py::capsule owner(points.data(), [](void*) {});  // the harness owns the memory
  py::array_t<double> P({n, py::ssize_t(3)}, {py::ssize_t(sizeof(Vec3d)), py::ssize_t(sizeof(double))},
                        reinterpret_cast<const double*>(points.data()), owner);
  py::detail::array_proxy(P.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return std::move(P);
}

bool PythonMethod::inside(const Vec3d& p) {
  return call("inside", [&] {
    if (!inside_one_.is_none()) return truth(inside_one_(py::make_tuple(p.x, p.y, p.z)), "inside_one(p) at " + point_text(p));
    std::vector<Vec3d> one{p};
    py::array checked = python_runtime().host.attr("check_inside")(instance_.attr("inside")(points_array(one)), 1);
    return *static_cast<const std::uint8_t*>(checked.data()) != 0;
  });
}

DistanceResult PythonMethod::distance(const Vec3d& p) {
  return call("distance", [&] {
    DistanceResult d;
    if (!distance_one_.is_none()) {
      const std::string what = "distance_one(p) at " + point_text(p);
      py::object r = distance_one_(py::make_tuple(p.x, p.y, p.z));
      if (!PySequence_Check(r.ptr()) || PySequence_Size(r.ptr()) != 4) {
        PyErr_Clear();
        throw std::runtime_error(what + ": expected (signed, closest, normal, triangle), got " + Py_TYPE(r.ptr())->tp_name);
      }
      py::object f[4];
      for (int i = 0; i < 4; ++i) {
        f[i] = py::reinterpret_steal<py::object>(PySequence_GetItem(r.ptr(), i));
        if (!f[i]) throw py::error_already_set();
      }
      d.distance = finite_number(f[0].ptr(), what + " signed");
      d.closest = finite_vec3(f[1].ptr(), what + " closest");
      d.normal = finite_vec3(f[2].ptr(), what + " normal");
      PyObject* idx = PyNumber_Index(f[3].ptr());
      if (!idx) {
        PyErr_Clear();
        throw std::runtime_error(what + " triangle: not an integer (" + Py_TYPE(f[3].ptr())->tp_name + ")");
      }
      d.triangle = PyLong_AsLongLong(idx);
      Py_DECREF(idx);
      return d;
    }
    std::vector<Vec3d> one{p};
    std::vector<DistanceResult> out(1);
    py::tuple checked = python_runtime().host.attr("check_distance")(instance_.attr("distance")(points_array(one)), 1);
    const auto* s = static_cast<const double*>(py::array(checked[0]).data());
    const auto* c = static_cast<const double*>(py::array(checked[1]).data());
    const auto* nrm = static_cast<const double*>(py::array(checked[2]).data());
    const auto* t = static_cast<const std::int64_t*>(py::array(checked[3]).data());
    d.distance = s[0];
    d.closest = {c[0], c[1], c[2]};
    d.normal = {nrm[0], nrm[1], nrm[2]};
    d.triangle = t[0];
    return d;
  });
}

void PythonMethod::inside_batch(const std::vector<Vec3d>& points, std::vector<std::uint8_t>& inside) {
  call("inside(P)", [&] {
    py::object r = instance_.attr("inside")(points_array(points));
    py::array checked = python_runtime().host.attr("check_inside")(r, points.size());
    inside.resize(points.size());
    if (!points.empty()) std::memcpy(inside.data(), checked.data(), points.size());
    return 0;
  });
}

void PythonMethod::distance_batch(const std::vector<Vec3d>& points, std::vector<DistanceResult>& out) {
  call("distance(P)", [&] {
    py::object r = instance_.attr("distance")(points_array(points));
    py::tuple checked = python_runtime().host.attr("check_distance")(r, points.size());
    const auto* s = static_cast<const double*>(py::array(checked[0]).data());
    const auto* c = static_cast<const double*>(py::array(checked[1]).data());
    const auto* nrm = static_cast<const double*>(py::array(checked[2]).data());
    const auto* t = static_cast<const std::int64_t*>(py::array(checked[3]).data());
    out.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      out[i].distance = s[i];
      out[i].closest = {c[3 * i], c[3 * i + 1], c[3 * i + 2]};
      out[i].normal = {nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]};
      out[i].triangle = t[i];
    }
    return 0;
  });
}

bool PythonMethod::supports(QueryType q) const {
  const bool declared = q == QueryType::inside ? decl_.caps.inside : decl_.caps.distance;
  if (!declared) return false;
  return call("supports", [&] {
    if (!py::hasattr(instance_, "supports")) return true;
    return truth(instance_.attr("supports")(to_string(q)), "supports(query)");
  });
}

void PythonMethod::reset_path() {
  call("reset_path", [&] {
    if (py::hasattr(instance_, "reset_path")) instance_.attr("reset_path")();
    return 0;
  });
}

std::size_t PythonMethod::structure_bytes() const {
  return call("structure_bytes", [&]() -> std::size_t {
    if (!py::hasattr(instance_, "structure_bytes")) return 0;
    const long long b = instance_.attr("structure_bytes")().cast<long long>();
    if (b < 0) throw std::runtime_error(decl_.name + ": structure_bytes() is negative");
    return std::size_t(b);
  });
}

std::vector<Counter> PythonMethod::counters() const {
  return call("counters", [&] {
    std::vector<Counter> out;
    if (!py::hasattr(instance_, "counters")) return out;
    for (auto item : instance_.attr("counters")().cast<py::dict>()) {
      const long long v = item.second.cast<long long>();
      if (v < 0) throw std::runtime_error("counters(): " + item.first.cast<std::string>() + " is negative");
      out.push_back({item.first.cast<std::string>(), std::uint64_t(v)});
    }
    return out;
  });
}

void PythonMethod::reset_counters() {
  call("reset_counters", [&] {
    if (py::hasattr(instance_, "reset_counters")) instance_.attr("reset_counters")();
    return 0;
  });
}

nlohmann::json PythonMethod::info() const {
  return call("info", [&] {
    nlohmann::json j = nlohmann::json::object();
    if (py::hasattr(instance_, "info")) {
      // Through JSON text, with str() for what JSON has no type for (numpy scalars, paths).
      py::object text = py::module_::import("json").attr("dumps")(
          instance_.attr("info")(), py::arg("default") = py::module_::import("builtins").attr("str"));
      j = nlohmann::json::parse(text.cast<std::string>());
      if (!j.is_object()) throw std::runtime_error("info() must return a dict");
    }
    auto per_query = [&](bool has_one, const char* one, const char* many) {
      return batch_ ? std::string("none: batch, one call per pass") : has_one ? one : many;
    };
    j["python"] = {{"module", decl_.folder + "/method.py"},
                   {"inside_call", per_query(!inside_one_.is_none(), "inside_one(p)", "inside(P) of one row")},
                   {"distance_call", per_query(!distance_one_.is_none(), "distance_one(p)", "distance(P) of one row")},
                   {"packages", python_runtime().packages}};
    return j;
  });
}

}  // namespace bvhbench
