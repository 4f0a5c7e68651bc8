"""Loading a result set (`results/NAME/`) into plain Python objects.

The per-job JSON files in `runs/` are authoritative; their fields are described once, in
harness/run/result_schema.json (result_schema.py; docs/results.md), and a reader here can only
ask for a described field. `summary.csv` is only cross-checked. Nothing here assumes a block is present: failed jobs have no `queries`,
jobs without an oracle have `accuracy: null`, methods report free-form `structure` blocks.
Every accessor returns None when a value is missing, so charts can simply skip it.
"""
import csv
import json
import os
import re
import sys
import tempfile
from collections import OrderedDict

import result_schema

OK = "ok"
KNOWN_STATUSES = result_schema.STATUSES  # harness/run/result_schema.json: the one list

# Method order in legends and tables: the star first, then peers, then anything new (sorted).
METHOD_ORDER = ["ebp_octree", "cgal_aabb", "embree", "openvdb", "brute_force"]

# Names that mark a mesh as a stress case (degenerate, broken, adversarial input): only for
# results that do not carry the dataset manifest's kind (job.mesh.dataset.kind; Job.is_stress).
STRESS_NAME_RE = re.compile(
    r"stress|stability|degenerate|(^|_)open(_|$)|nonmanifold|non_manifold|self_?intersect|"
    r"sliver|needle", re.IGNORECASE)


def method_sort_key(method):
    if method in METHOD_ORDER:
        return (METHOD_ORDER.index(method), method)
    return (len(METHOD_ORDER), method)


class ReportError(Exception):
    """A problem with the input that the user must fix (reported with exit code 2)."""


def dig(d, path, default=None):
    """d['a']['b']['c'] for path 'a.b.c', or default when any step is missing or null."""
    cur = d
    for key in path.split("."):
        if not isinstance(cur, dict) or key not in cur or cur[key] is None:
            return default
        cur = cur[key]
    return cur


def as_str(x, default=""):
    """A text field; anything else (null, number, object) becomes the default or its str()."""
    if x is None or isinstance(x, (dict, list)):
        return default
    return str(x)


def as_float(x):
    if isinstance(x, bool):
        return None
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if v == v else None  # NaN -> None


def median(values):
    """The median of the values that are not None, as the harness computes its own (the mean
    of the middle two for an even count); None when there are none."""
    v = sorted(x for x in values if x is not None)
    if not v:
        return None
    mid = len(v) // 2
    return v[mid] if len(v) % 2 else (v[mid - 1] + v[mid]) / 2


class Job:
    """One result file. `raw` is the parsed JSON; properties read it defensively."""

    def __init__(self, raw, path):
        self.raw = raw
        self.path = path

    def get(self, path, default=None):
        """The value at a dotted path of the schema (SchemaError for a path it does not
        describe), or default when the file lacks it."""
        result_schema.require_described(path)
        return dig(self.raw, path, default)

    def num(self, path):
        return as_float(self.get(path))

    # --- identity -------------------------------------------------------------------------
    @property
    def id(self):
        return as_str(self.get("job.id")) or os.path.splitext(os.path.basename(self.path))[0]

    @property
    def method(self):
        return (as_str(self.get("job.method"))
                or as_str(self.get("job.method_spec"), "?").split(":")[0] or "?")

    @property
    def params_key(self):
        key = self.get("job.params_key")
        if not isinstance(key, str):
            spec = as_str(self.get("job.method_spec"))
            key = spec.split(":", 1)[1] if ":" in spec else ""
        return key

    @property
    def config(self):
        """A method with its non-default parameters, e.g. 'ebp_octree:leaf_factor=5'."""
        return self.method + (":" + self.params_key if self.params_key else "")

    @property
    def query(self):
        return as_str(self.get("job.query"), "?") or "?"

    @property
    def threads(self):
        """Query threads (job.threads; 1 in results older than the thread axis)."""
        t = self.num("job.threads")
        return int(t) if t and t >= 1 else 1

    @property
    def kind(self):
        return as_str(self.get("job.queries.kind"), "?") or "?"

    @property
    def mesh(self):
        name = as_str(self.get("job.mesh.name"))
        if name:
            return name
        path = as_str(self.get("job.mesh.path"), "?") or "?"
        return os.path.splitext(os.path.basename(path))[0]

    @property
    def triangles(self):
        return self.num("job.mesh.triangles")

    @property
    def status(self):
        return as_str(self.get("status"), "error") or "error"

    @property
    def ok(self):
        return self.status == OK

    @property
    def message(self):
        return as_str(self.get("message"))

    # --- measurements (None when absent) --------------------------------------------------
    @property
    def qps(self):
        v = self.num("queries.throughput_qps.median")
        return v if v and v > 0 else None

    @property
    def n_queries(self):
        return self.num("queries.n") or self.num("job.queries.n")

    @property
    def build_seconds(self):
        return self.num("build.seconds")

    @property
    def structure_bytes(self):
        return self.num("build.structure_bytes") or self.num("memory.structure_bytes")

    @property
    def peak_rss_bytes(self):
        return self.num("memory.peak_rss_bytes") or self.num("build.peak_rss_bytes")

    @property
    def file_bytes(self):
        return self.num("structure.file_bytes")

    @property
    def has_accuracy(self):
        return isinstance(self.get("accuracy"), dict)

    def is_stress(self):
        """Is the job's mesh a stress case? As the dataset manifest says (job.mesh.dataset: kind
        stress, or not closed; recorded by the runner where the manifest beside the mesh lists
        these very bytes); the mesh's name only for results made without a manifest."""
        kind = self.get("job.mesh.dataset.kind")
        if isinstance(kind, str):  # a stress case by construction, or an open mesh (a scan)
            return kind == "stress" or self.get("job.mesh.dataset.closed") is False
        return bool(STRESS_NAME_RE.search(self.mesh))


class ResultSet:
    """All jobs of one suite run, plus what could not be read."""

    def __init__(self, root, jobs, unreadable, summary_only):
        self.root = root
        self.name = os.path.basename(os.path.normpath(root))
        self.jobs = jobs
        self.unreadable = unreadable          # [(file, reason)]
        self.summary_only = summary_only      # job ids in summary.csv with no JSON
        self.stress_meshes = self._find_stress_meshes()

    # --- views ---------------------------------------------------------------------------
    @property
    def ok_jobs(self):
        return [j for j in self.jobs if j.ok]

    @property
    def failed_jobs(self):
        return [j for j in self.jobs if not j.ok]

    def model_jobs(self):
        """Single-thread jobs on regular models (not stress cases): what the scaling charts and
        tables use. Jobs on more threads are the thread-scaling chart's (thread_jobs)."""
        return [j for j in self.jobs if j.mesh not in self.stress_meshes and j.threads == 1]

    def thread_jobs(self):
        """Jobs on regular models of every thread count: the thread axis."""
        return [j for j in self.jobs if j.mesh not in self.stress_meshes]

    def meshes(self, jobs=None):
        """Mesh names sorted by triangle count."""
        sizes = OrderedDict()
        for j in (self.jobs if jobs is None else jobs):
            if j.mesh not in sizes or (sizes[j.mesh] is None and j.triangles):
                sizes[j.mesh] = j.triangles
        return sorted(sizes, key=lambda m: (sizes[m] or 0, m))

    def mesh_triangles(self, mesh):
        for j in self.jobs:
            if j.mesh == mesh and j.triangles:
                return j.triangles
        return None

    def is_stability_suite(self):
        return bool(self.stress_meshes)

    def _find_stress_meshes(self):
        meshes = self.meshes()
        suites = {str(j.get("job.suite", "")) for j in self.jobs} | {self.name}
        if any(re.search(r"stability|stress", s, re.I) for s in suites):
            return set(meshes)
        stress = {j.mesh for j in self.jobs if j.is_stress()}
        if stress:
            return stress
        # A suite where many meshes end in non-ok statuses (other than 'unsupported') for a
        # good share of their jobs is a stress suite too, whatever its meshes are called.
        bad = set()
        for m in meshes:
            js = [j for j in self.jobs if j.mesh == m]
            failing = [j for j in js if j.status not in (OK, "unsupported")]
            if len(failing) * 3 >= len(js):
                bad.add(m)
        if len(meshes) >= 3 and len(bad) >= max(3, len(meshes) // 2):
            return set(meshes)
        return set()

    def contexts(self):
        """The machine(s) and run(s) behind the results, one dict per machine and build.

        Jobs of one suite carry their own dates (and, on a tree being edited, commits), so a
        context gathers them: first and last date, the distinct commits, any dirty flag.
        """
        groups = OrderedDict()
        for j in self.jobs:
            c = {k: as_str(j.get("context." + k)) for k in CONTEXT_KEYS}
            key = tuple(c[k] for k in MACHINE_KEYS)
            g = groups.setdefault(key, dict(zip(MACHINE_KEYS, key), dates=[], commits=[],
                                             dirty=False, jobs=0))
            g["jobs"] += 1
            if c["date"]:
                g["dates"].append(c["date"])
            if c["git_commit"] and c["git_commit"] not in g["commits"]:
                g["commits"].append(c["git_commit"])
            g["dirty"] |= c["git_dirty"].lower() == "true"
        out = []
        for g in groups.values():
            dates = sorted(g.pop("dates"))
            g["date_first"], g["date_last"] = (dates[0], dates[-1]) if dates else ("", "")
            out.append(g)
        return sorted(out, key=lambda c: -c["jobs"])


CONTEXT_KEYS = ("host", "cpu_model", "cores", "date", "git_commit", "git_dirty", "compiler",
                "build_type", "bvhbench_version")
# What makes two results comparable "machine-wise"; dates and commits vary within a suite.
MACHINE_KEYS = ("host", "cpu_model", "cores", "compiler", "build_type", "bvhbench_version")


def load(root):
    """Read results/NAME. Raises ReportError when there is nothing to report on."""
    if not os.path.isdir(root):
        raise ReportError(f"{root}: no such result directory")
    runs = os.path.join(root, "runs")
    if not os.path.isdir(runs):
        raise ReportError(f"{runs}: missing; expected one JSON file per job "
                          "(written by `bvhbench suite`)")
    files = sorted(f for f in os.listdir(runs) if f.endswith(".json"))
    jobs, unreadable = [], []
    for f in files:
        path = os.path.join(runs, f)
        try:
            with open(path, encoding="utf-8") as fh:
                raw = json.load(fh)
            if not isinstance(raw, dict):
                raise ValueError("top level is not an object")
        except (OSError, ValueError) as e:
            unreadable.append((f, str(e)))
            print(f"warning: {path}: unreadable result file: {e}", file=sys.stderr)
            continue
        departures = result_schema.problems(raw)
        if departures:
            more = f" (and {len(departures) - 1} more)" if len(departures) > 1 else ""
            print(f"warning: {path}: {departures[0]}{more}", file=sys.stderr)
        jobs.append(Job(raw, path))
    if not jobs:
        why = "contains no result files" if not files else "contains no readable result files"
        raise ReportError(f"{runs}: {why}; run a suite first (e.g. `make bench`)")
    known = {j.id for j in jobs}
    summary_only = [jid for jid in _summary_ids(os.path.join(root, "summary.csv"))
                    if jid not in known]
    return ResultSet(root, jobs, unreadable, summary_only)


def write_atomic(path, text):
    """Write a text file as the harness does (harness/util/atomic_file.hpp): to a temporary of
    its own in the same folder, then renamed, so that a reader never sees half a file and two
    writers of one path never share a temporary."""
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=os.path.basename(path) + ".tmp.")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _summary_ids(path):
    if not os.path.isfile(path):
        return []
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            return [row.get("job_id", "") for row in csv.DictReader(fh) if row.get("job_id")]
    except (OSError, csv.Error) as e:
        print(f"warning: {path}: {e}", file=sys.stderr)
        return []


def representative_configs(jobs):
    """method -> the one configuration that stands for it in scaling charts and tables.

    The default configuration (empty params_key) when the suite ran it; otherwise the
    configuration run on the most models, ties broken by the higher median throughput.
    """
    by_method = {}
    for j in jobs:
        by_method.setdefault(j.method, {}).setdefault(j.params_key, []).append(j)
    chosen = {}
    for method, configs in by_method.items():
        if "" in configs:
            chosen[method] = ""
            continue

        def score(item):
            key, js = item
            med = median(j.qps for j in js if j.ok) or 0.0
            return (len({j.mesh for j in js if j.ok}), med, key)

        chosen[method] = max(configs.items(), key=score)[0]
    return chosen


def _without_variant(key):
    return ",".join(p for p in key.split(",")
                    if p and not p.startswith("coherent=") and not p.startswith("batch="))


def is_coherent(key):
    return "coherent=true" in key.split(",")


def is_batch(key):
    """A Python method's batch row (batch=true): the whole query set answered per call."""
    return "batch=true" in key.split(",")


def config_label(config, key):
    """A configuration as tables show it: batch rows marked, so that no one reads a per-call
    throughput as a per-query one."""
    return config + (" [batch]" if is_batch(key) else "")


def shown_configs(jobs):
    """[(method, params_key)] that stand for each method in scaling charts and tables: the
    representative configuration, plus its path-coherent variant (coherent=true) and its batch
    variant (batch=true) when the suite ran them, since each is its own row
    (docs/architecture.md, "Contracts": queries)."""
    reps = representative_configs(jobs)
    keys = {}
    for j in jobs:
        keys.setdefault(j.method, set()).add(j.params_key)
    out = []
    for method in sorted(reps, key=method_sort_key):
        rep = reps[method]
        out.append((method, rep))
        out += [(method, k) for k in sorted(keys[method])
                if k != rep and (is_coherent(k) and not is_coherent(rep) or is_batch(k) and not is_batch(rep))
                and _without_variant(k) == _without_variant(rep)]
    return out
