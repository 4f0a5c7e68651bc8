"""The Python side of bvhbench's host for methods written in Python (methods/README.md).

The C++ host (python_method.cpp) embeds the interpreter and calls these functions; it never names a
method. A Python method is a folder holding `method.py` with module-level literal declarations
(DESCRIPTION, REQUIRES, CAPABILITIES, PARAMETERS, optionally SWEEP) and a class `Method`.

Why the declarations are literals read with `ast`: `bvhbench methods`, `run` and every suite job
make the registry, and importing trimesh or igl costs seconds; reading literals costs
milliseconds, and `importlib.util.find_spec` says whether a required package is installed
without importing it. The module itself is imported only when its method is created.
"""
import ast
import importlib.metadata
import importlib.util
import os
import sys

DECLARED = ("DESCRIPTION", "REQUIRES", "CAPABILITIES", "PARAMETERS")
# SWEEP: the default sweep of `methods: all` suites; INSIDE: what its inside means, per
# configuration (methods/README.md, "What inside means").
OPTIONAL = ("SWEEP", "INSIDE")
PARAM_TYPES = ("integer", "real", "boolean", "text", "choice")
PARAM_ROLES = ("build", "query")  # shapes the structure, or only how it is queried
TYPE_ALIASES = {"int": "integer", "bool": "boolean"}  # the names `bvhbench methods` shows
CAPABILITY_KEYS = ("inside", "distance", "closest_triangle")
# The names harness/core/inside_definition.hpp reads (to_string of InsideRule, InputContract).
INSIDE_RULES = ("ray_parity", "winding_number", "nonzero_winding", "generalized_winding_number")
INSIDE_CONTRACTS = ("any", "closed", "closed_oriented", "closed_oriented_manifold", "embedded")
INSIDE_KEYS = ("when", "definition", "approximate", "threshold", "threshold_option", "contract")


class SetupError(Exception):
    """The packages' environment cannot be used (the message says which and why)."""


def _pyvenv_cfg(venv):
    values = {}
    with open(os.path.join(venv, "pyvenv.cfg"), encoding="utf-8", errors="replace") as f:
        for line in f:
            key, sep, value = line.partition("=")
            if sep:
                values[key.strip()] = value.strip()
    return values


def set_up_packages(venv, how):
    """Puts the packages the methods import on sys.path and says, in one sentence, what it used.

    `venv` is a virtual environment's folder ('' for none) and `how` why it was chosen. The
    interpreter runs isolated (no PYTHON* variables, no user site, `site` not imported), so
    nothing but this decides where numpy and the methods' packages come from: the venv's
    site-packages (and the system's when its pyvenv.cfg includes them), or, without a venv, the
    system's. Raises SetupError when the venv cannot be used."""
    import site
    version = sys.version.split()[0]
    minor = f"{sys.version_info.major}.{sys.version_info.minor}"
    if not venv:
        site.main()
        return f"Python methods: Python {version} (embedded), system packages only ({how})"
    if not os.path.isfile(os.path.join(venv, "pyvenv.cfg")):
        raise SetupError(f"{venv} ({how}) is not a virtual environment (no pyvenv.cfg)")
    cfg = _pyvenv_cfg(venv)
    made = cfg.get("version") or cfg.get("version_info") or ""
    if made and ".".join(made.split(".")[:2]) != minor:
        raise SetupError(f"{venv} ({how}) was made from Python {made}, but bvhbench embeds Python "
                         f"{version}: its compiled packages cannot load here (make the venv from a "
                         f"Python {minor}, or build bvhbench against the other Python's libpython)")
    site_dir = os.path.join(venv, "lib", f"python{minor}", "site-packages")
    if not os.path.isdir(site_dir):
        raise SetupError(f"{venv} ({how}) has no {site_dir}")
    site.addsitedir(site_dir)  # with its .pth files
    if cfg.get("include-system-site-packages", "false").lower() == "true":
        for d in site.getsitepackages():
            site.addsitedir(d)
    return (f"Python methods: Python {version} (embedded), packages from {site_dir} ({how}; "
            f"the venv was made from Python {made or 'unknown'})")


class DeclarationError(Exception):
    """method.py's declarations are missing or malformed (the message names the file)."""


def read_declarations(folder):
    """The declarations of `folder`/method.py, checked, without importing the module.

    Returns a dict: name (the folder's name), description (str), requires (list of top-level
    module names), capabilities (dict of CAPABILITY_KEYS -> bool), parameters (list of dicts with
    name, type, role, default (str), help, choices, min, max), sweep (list of "k=v,k=v" texts:
    the variants a `methods: all` suite runs; [""] when SWEEP is not declared), missing (the required modules
    `find_spec` cannot find), path. Raises DeclarationError naming the file and the problem."""
    path = os.path.join(folder, "method.py")
    try:
        with open(path, "rb") as f:
            tree = ast.parse(f.read(), path)
    except (OSError, SyntaxError, ValueError) as e:
        raise DeclarationError(f"{path}: cannot be read as Python: {e}") from None
    found = {}
    for node in tree.body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name) and node.targets[0].id in DECLARED + OPTIONAL):
            try:
                found[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                raise DeclarationError(f"{path}: {node.targets[0].id} must be a literal "
                                       "(the harness reads it without importing the module)") from None
    for key in DECLARED:
        if key not in found:
            raise DeclarationError(f"{path}: no module-level {key} = ... declaration")
    if not any(isinstance(n, ast.ClassDef) and n.name == "Method" for n in tree.body):
        raise DeclarationError(f"{path}: no class Method")

    description = found["DESCRIPTION"]
    if not isinstance(description, str):
        raise DeclarationError(f"{path}: DESCRIPTION must be a string")
    requires = found["REQUIRES"]
    if not (isinstance(requires, (list, tuple)) and all(isinstance(r, str) and r and "." not in r
                                                        for r in requires)):
        raise DeclarationError(f"{path}: REQUIRES must be a list of top-level module names")
    caps = found["CAPABILITIES"]
    if not isinstance(caps, dict) or any(k not in CAPABILITY_KEYS or not isinstance(v, bool)
                                         for k, v in caps.items()):
        raise DeclarationError(f"{path}: CAPABILITIES must map some of {CAPABILITY_KEYS} to booleans")
    params = []
    for i, p in enumerate(found["PARAMETERS"]):
        if not isinstance(p, dict) or not {"name", "type", "role", "default", "help"} <= set(p):
            raise DeclarationError(f"{path}: PARAMETERS[{i}] must be a dict with name, type, "
                                   "role, default and help")
        if p["role"] not in PARAM_ROLES:
            raise DeclarationError(f"{path}: parameter {p['name']!r}: role must be one of {PARAM_ROLES} "
                                   "(build: it shapes the structure; query: only how it is asked)")
        p = dict(p, type=TYPE_ALIASES.get(p["type"], p["type"]))
        if p["type"] not in PARAM_TYPES:
            raise DeclarationError(f"{path}: parameter {p['name']!r}: type must be one of {PARAM_TYPES}")
        if p["name"] == "batch":
            raise DeclarationError(f"{path}: parameter 'batch' is the harness's own")
        default = p["default"]
        default = ("true" if default else "false") if isinstance(default, bool) else str(default)
        params.append({"name": str(p["name"]), "type": p["type"], "role": p["role"], "default": default,
                       "help": str(p["help"]), "choices": [str(c) for c in p.get("choices", [])],
                       "min": float(p.get("min", -1e308)), "max": float(p.get("max", 1e308))})
    sweep = found.get("SWEEP", [""])
    if not (isinstance(sweep, (list, tuple)) and all(isinstance(e, str) for e in sweep)):
        raise DeclarationError(f"{path}: SWEEP must be a list of parameter texts (\"k=v,k=v\"; \"\" = defaults)")
    inside = _inside_declaration(path, found.get("INSIDE", []), {p["name"] for p in params})
    missing = [r for r in requires if importlib.util.find_spec(r) is None]
    return {"inside": inside, "name": os.path.basename(os.path.normpath(folder)), "description": description,
            "requires": list(requires), "capabilities": {k: caps.get(k, False) for k in CAPABILITY_KEYS},
            "parameters": params, "sweep": list(sweep), "missing": missing, "path": path}


def _inside_declaration(path, declared, options):
    """INSIDE, checked: a list of {"when": {option: value}, "definition", "approximate",
    "threshold", "threshold_option", "contract"}, the first matching configuration's entry
    applying; every value normalised to a string for the C++ side."""
    if not isinstance(declared, (list, tuple)):
        raise DeclarationError(f"{path}: INSIDE must be a list of dicts")
    out = []
    for i, d in enumerate(declared):
        where = f"{path}: INSIDE[{i}]"
        if not isinstance(d, dict) or not {"definition", "contract"} <= set(d) or set(d) - set(INSIDE_KEYS):
            raise DeclarationError(f"{where} must be a dict with definition and contract (and "
                                   f"optionally when, approximate, threshold, threshold_option)")
        if d["definition"] not in INSIDE_RULES:
            raise DeclarationError(f"{where}: definition must be one of {INSIDE_RULES}")
        if d["contract"] not in INSIDE_CONTRACTS:
            raise DeclarationError(f"{where}: contract must be one of {INSIDE_CONTRACTS}")
        when = d.get("when", {})
        if not isinstance(when, dict) or any(k not in options for k in when):
            raise DeclarationError(f"{where}: when must map options of PARAMETERS to values")
        option = d.get("threshold_option", "")
        if option and option not in options:
            raise DeclarationError(f"{where}: threshold_option {option!r} is not an option of PARAMETERS")
        if not isinstance(d.get("approximate", False), bool):
            raise DeclarationError(f"{where}: approximate must be a boolean")
        out.append({"when": {str(k): ("true" if v is True else "false" if v is False else str(v))
                             for k, v in when.items()},
                    "definition": d["definition"], "contract": d["contract"],
                    "approximate": d.get("approximate", False),
                    "threshold": float(d.get("threshold", 0.5)), "threshold_option": option})
    return out


def module_version(name):
    """The installed version of top-level module `name` (its distribution's), or ''."""
    mod = sys.modules.get(name)
    version = getattr(mod, "__version__", None)
    if isinstance(version, str):
        return version
    for dist in importlib.metadata.packages_distributions().get(name, []):
        try:
            return importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            pass
    return ""


def create(folder, values):
    """Imports `folder`/method.py under a name of its own and returns (instance, versions).

    `values` maps every declared parameter to its value, typed by the C++ Params from the
    declaration (int, float, bool or str); the instance is `Method(**values)`. `versions` maps each required module to its installed version."""
    decl = read_declarations(folder)
    name = "bvhbench_method_" + decl["name"]
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, decl["path"])
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    declared = {p["name"] for p in decl["parameters"]}
    instance = module.Method(**{k: v for k, v in values.items() if k in declared})
    versions = {r: module_version(r) for r in decl["requires"]}
    return instance, versions


class AnswerError(Exception):
    """A method's answer has the wrong type, shape or a non-finite value."""


def _array(np, value, what, shape, dtype):
    try:
        a = np.asarray(value)
    except Exception as e:  # an object numpy cannot read
        raise AnswerError(f"{what}: not an array ({type(value).__name__}: {e})") from None
    if a.shape != shape:
        raise AnswerError(f"{what}: shape {a.shape}, expected {shape}")
    if dtype == "bool":
        if a.dtype != np.bool_ and not np.issubdtype(a.dtype, np.integer):
            raise AnswerError(f"{what}: dtype {a.dtype}, expected bool")
        return np.ascontiguousarray(a != 0, dtype=np.uint8)
    if dtype == "int64":
        if not np.issubdtype(a.dtype, np.integer):
            raise AnswerError(f"{what}: dtype {a.dtype}, expected an integer type")
        return np.ascontiguousarray(a, dtype=np.int64)
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise AnswerError(f"{what}: dtype {a.dtype}, expected float")
    a = np.ascontiguousarray(a, dtype=np.float64)
    bad = ~np.isfinite(a)
    if bad.any():
        i = int(np.argwhere(bad)[0][0])
        raise AnswerError(f"{what}: {a.reshape(len(a), -1)[i]} at query {i} is not finite")
    return a


def check_inside(answer, n):
    """`Method.inside(P)`'s answer as a C-contiguous (n,) uint8 array, or AnswerError."""
    import numpy as np
    return _array(np, answer, "inside(P)", (n,), "bool")


def check_distance(answer, n):
    """`Method.distance(P)`'s answer (signed, closest, normal, triangle) as C-contiguous float64
    (n,), (n, 3), (n, 3) and int64 (n,) arrays, or AnswerError."""
    import numpy as np
    if not isinstance(answer, (tuple, list)) or len(answer) != 4:
        raise AnswerError("distance(P): expected a tuple (signed, closest, normal, triangle), got "
                          f"{type(answer).__name__}")
    return (_array(np, answer[0], "distance(P) signed", (n,), "float"),
            _array(np, answer[1], "distance(P) closest", (n, 3), "float"),
            _array(np, answer[2], "distance(P) normal", (n, 3), "float"),
            _array(np, answer[3], "distance(P) triangle", (n,), "int64"))


def describe_exception(e, tb=None):
    """One line: the exception's type and message, and where it was raised (the innermost frame
    of traceback `tb`, default the exception's own)."""
    import traceback
    where = ""
    frames = traceback.extract_tb(tb if tb is not None else e.__traceback__)
    if frames:
        # The method's own line when it is on the stack (the library's frames below it say less).
        own = [f for f in frames if os.path.basename(f.filename) == "method.py"]
        f = own[-1] if own else frames[-1]
        where = f" (at {os.path.basename(f.filename)}:{f.lineno} in {f.name})"
    text = str(e) or "(no message)"
    return f"{type(e).__name__}: {text}{where}"

