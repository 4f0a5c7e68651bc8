#pragma once
/// The interpreter embedded in bvhbench to host the methods written in Python: started once per
/// process, on first use, and never finalised (numpy and the libraries do not survive a restart).
///
/// Where the methods' packages come from, in this order: the virtual environment named by
/// BVHBENCH_PYTHON_VENV; the activated one (VIRTUAL_ENV); the project's own `.venv/` (the one
/// `make deps` makes); else the system's. The interpreter runs isolated (PYTHONPATH, PYTHONHOME
/// and the user site are ignored), so nothing else decides it.
#include <string>

#include <pybind11/pybind11.h>

namespace bvhbench {

struct PythonRuntime {
  bool ok = false;
  std::string problem;   ///< why Python methods cannot run here (when !ok)
  std::string version;   ///< the embedded interpreter's, e.g. "3.11.2"
  std::string packages;  ///< one sentence: interpreter and the site-packages used, and why
  /// bvhbench_python_host.py, imported. Only touched with the GIL held (pybind11::gil_scoped_acquire).
  pybind11::object host;
};

/// The runtime, started on the first call (thread-safe). After start the GIL is released: every
/// caller takes it with pybind11::gil_scoped_acquire around its Python calls.
const PythonRuntime& python_runtime();

/// The pending Python exception as one line (type, message, where it was raised), clearing it.
/// Call with the GIL held, from a `catch (pybind11::error_already_set&)`.
std::string python_error_text(pybind11::error_already_set& e);

}  // namespace bvhbench
