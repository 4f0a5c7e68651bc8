// Registers the methods written in Python: the folders named by bvhbench_python_method() in
// methods/CMakeLists.txt, and those in BVHBENCH_PYTHON_METHODS (folders separated by ':', to try a
// method without rebuilding). A folder that cannot be offered (its package is not installed, its
// declarations are malformed, Python cannot start) is left out with a note, never an error.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include <pybind11/stl.h>

#include "harness/core/registry.hpp"
#include "python_method.hpp"
#include "python_runtime.hpp"

namespace py = pybind11;

namespace bvhbench {
std::vector<std::string> python_method_folders();  // generated from methods/CMakeLists.txt
}

namespace {

using namespace bvhbench;

ParamType param_type(const std::string& t) {
  if (t == "integer") return ParamType::integer;
  if (t == "real") return ParamType::real;
  if (t == "boolean") return ParamType::boolean;
  if (t == "choice") return ParamType::choice;
  return ParamType::text;
}

bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

MethodInfo method_info(const py::dict& d, const std::string& folder) {
  MethodInfo m = MethodInfo::named(d["name"].cast<std::string>(),
                                   d["description"].cast<std::string>() + " [Python]");
  py::dict caps = d["capabilities"];
  PythonMethodDeclaration decl;
  decl.name = m.name;
  decl.folder = folder;
  decl.caps.inside = caps["inside"].cast<bool>();
  decl.caps.distance = caps["distance"].cast<bool>();
  decl.caps.closest_triangle = caps["closest_triangle"].cast<bool>();
  m.caps = decl.caps;
  m.caps.build_threads = BuildThreads::library;  // numpy and the library pick their own
  for (auto p : d["parameters"].cast<py::list>()) {
    py::dict pd = p.cast<py::dict>();
    ParamSpec s;
    s.name = pd["name"].cast<std::string>();
    s.type = param_type(pd["type"].cast<std::string>());
    s.role = pd["role"].cast<std::string>() == "query" ? ParamRole::query : ParamRole::build;
    s.default_value = pd["default"].cast<std::string>();
    s.help = pd["help"].cast<std::string>();
    s.choices = pd["choices"].cast<std::vector<std::string>>();
    s.min = pd["min"].cast<double>();
    s.max = pd["max"].cast<double>();
    m.params.push_back(std::move(s));
  }
  // The harness's own parameter of every Python method: its own row, like coherent=true.
  m.params.push_back({"batch", ParamType::boolean, ParamRole::query, "false",
                      "answer the whole query set per call: throughput per whole-set call, no per-query latency",
                      {}, 0, 1});
  // A method that keeps state along a path says so as a `coherent` option (registry.hpp).
  m.caps.coherence = std::any_of(m.params.begin(), m.params.end(), [](const ParamSpec& s) { return s.name == "coherent"; });
  m.sweep = d["sweep"].cast<std::vector<std::string>>();
  for (auto v : d["inside"].cast<py::list>()) {
    py::dict vd = v.cast<py::dict>();
    InsideVariant iv;
    iv.when = vd["when"].cast<std::map<std::string, std::string>>();
    const std::string what = folder + "/method.py: INSIDE";
    iv.definition.rule = parse_inside_rule(vd["definition"].cast<std::string>(), what);
    iv.definition.contract = parse_input_contract(vd["contract"].cast<std::string>(), what);
    iv.definition.approximate = vd["approximate"].cast<bool>();
    iv.definition.threshold = vd["threshold"].cast<double>();
    iv.threshold_option = vd["threshold_option"].cast<std::string>();
    m.inside.push_back(std::move(iv));
  }
  m.create = [decl](const Params& p) { return std::make_unique<PythonMethod>(decl, p); };
  return m;
}

}  // namespace

void bvhbench_register_python_host(bvhbench::Registry& r) {
  std::vector<std::string> folders = python_method_folders();
  if (const char* extra = std::getenv("BVHBENCH_PYTHON_METHODS"); extra && *extra) {
    std::stringstream ss(extra);
    for (std::string f; std::getline(ss, f, ':');)
      if (!f.empty()) folders.push_back(f);
  }
  if (folders.empty()) return;
  auto name_of = [](const std::string& folder) {
    std::filesystem::path p = std::filesystem::path(folder).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();  // "dir/" normalises to "dir/" + ""
    return p.filename().string();
  };
  const PythonRuntime& rt = python_runtime();
  if (!rt.ok) {
    for (const auto& f : folders) r.add_left_out(name_of(f), rt.problem);
    return;
  }
  r.add_note(rt.packages);
  py::gil_scoped_acquire gil;
  for (const auto& folder : folders) {
    const std::string name = name_of(folder);
    if (!valid_name(name)) {
      r.add_left_out(name, "the folder " + folder + " is not a method name ([a-z0-9_]+)");
      continue;
    }
    if (r.find(name)) {
      r.add_left_out(name, "the folder " + folder + " has the name of a method already registered");
      continue;
    }
    try {
      py::dict d = rt.host.attr("read_declarations")(folder);
      auto missing = d["missing"].cast<std::vector<std::string>>();
      if (!missing.empty()) {
        r.add_left_out(name, "needs the Python module(s) " + joined(missing) +
                                 ", not installed (make deps installs what pyproject.toml lists; " + rt.packages + ")");
        continue;
      }
      MethodInfo m = method_info(d, folder);
      // A sweep entry that names no parameter or a bad value is the folder's mistake: said here,
      // when the method is found, not when a `methods: all` suite first expands it.
      if (const std::string bad = sweep_problem(m); !bad.empty()) {
        r.add_left_out(name, folder + "/method.py: SWEEP: " + bad);
        continue;
      }
      if (const std::string bad = coherence_problem(m); !bad.empty()) {
        r.add_left_out(name, folder + "/method.py: PARAMETERS: " + bad);
        continue;
      }
      if (const std::string bad = inside_declaration_problem(m); !bad.empty()) {
        r.add_left_out(name, folder + "/method.py: INSIDE: " + bad);
        continue;
      }
      r.add(std::move(m));
    } catch (py::error_already_set& e) {
      r.add_left_out(name, python_error_text(e));
    } catch (const py::cast_error& e) {
      r.add_left_out(name, folder + "/method.py: a declaration of an unexpected type (" + std::string(e.what()) + ")");
    }
  }
}
