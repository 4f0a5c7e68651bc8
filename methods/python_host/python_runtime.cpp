#include "python_runtime.hpp"

#include <Python.h>

#include <cstdlib>
#include <filesystem>

namespace py = pybind11;

namespace bvhbench {

namespace {

const py::object* g_host = nullptr;  // the host module once imported, for python_error_text()

/// The venv to use and why it was chosen ("" when there is none).
std::pair<std::string, std::string> choose_venv() {
  if (const char* v = std::getenv("BVHBENCH_PYTHON_VENV"); v && *v)
    return {v, "BVHBENCH_PYTHON_VENV"};
  if (const char* v = std::getenv("VIRTUAL_ENV"); v && *v) return {v, "VIRTUAL_ENV, the activated venv"};
  const std::string project = BVHBENCH_PROJECT_VENV;
  std::error_code ec;
  if (std::filesystem::exists(project + "/pyvenv.cfg", ec)) return {project, "the project's .venv"};
  return {"", "no BVHBENCH_PYTHON_VENV, no VIRTUAL_ENV, no " + project};
}

PythonRuntime* start() {
  auto* rt = new PythonRuntime;  // never destroyed: its objects must not be released after exit
  // Single thread unless a job asks for more, and Python methods do not declare that they may:
  // the libraries' own thread pools are held to one thread, unless the user set them.
  for (const char* var : {"IGL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                          "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"})
    setenv(var, "1", /*overwrite=*/0);
  PyConfig config;
  PyConfig_InitIsolatedConfig(&config);
  config.install_signal_handlers = 0;  // the harness owns SIGINT (run/interrupt.hpp)
  config.site_import = 0;              // set_up_packages() decides the site-packages
  config.parse_argv = 0;
  PyStatus status = PyConfig_SetString(&config, &config.program_name, L"bvhbench");
  if (!PyStatus_Exception(status)) status = Py_InitializeFromConfig(&config);
  PyConfig_Clear(&config);
  if (PyStatus_Exception(status)) {
    rt->problem = std::string("the embedded Python did not start: ") +
                  (status.err_msg ? status.err_msg : "unknown error");
    return rt;
  }
  rt->version = Py_GetVersion();
  rt->version = rt->version.substr(0, rt->version.find(' '));
  try {
    py::module_ sys = py::module_::import("sys");
    sys.attr("argv") = py::make_tuple("bvhbench");  // some libraries read sys.argv[0]
    // Extension modules bind to their own libraries first (RTLD_DEEPBIND). Without it a wheel's
    // library resolves symbols from what bvhbench already loaded: embreex's calls into its
    // Embree 4 went to the executable's Embree 3 (same names, other ABI) and crashed.
    py::module_ os = py::module_::import("os");
    sys.attr("setdlopenflags")(sys.attr("getdlopenflags")().cast<int>() | os.attr("RTLD_DEEPBIND").cast<int>());
    sys.attr("path").attr("insert")(0, BVHBENCH_PYTHON_HOST_DIR);
    rt->host = py::module_::import("bvhbench_python_host");
    g_host = &rt->host;
    auto [venv, how] = choose_venv();
    rt->packages = rt->host.attr("set_up_packages")(venv, how).cast<std::string>();
    rt->ok = true;
  } catch (py::error_already_set& e) {
    rt->problem = python_error_text(e);
  }
  PyEval_SaveThread();  // release the GIL: callers take it per call
  return rt;
}

}  // namespace

const PythonRuntime& python_runtime() {
  static PythonRuntime* rt = start();
  return *rt;
}

std::string python_error_text(py::error_already_set& e) {
  // The host's describe_exception() says where in the method it was raised; without the host (it
  // failed to import) pybind11's own text is the best there is.
  if (g_host) {
    try {
      return g_host->attr("describe_exception")(e.value(), e.trace()).cast<std::string>();
    } catch (py::error_already_set&) {
    }
  }
  return e.what();
}

}  // namespace bvhbench
