"""The report's first screen: per model and query, the fastest exact method and the EBP-Octree's
ratio to it; one accuracy line per method.

Exact is measured, not declared: a job's answers are exact when it was checked against the
oracle and is within the report's tolerances (tables.accuracy_problems). So a method is judged
by what it did in this run, and a new method needs nothing here.

A method configuration is *approximate by design* when most of its checked jobs answered wrongly
(a sampled field, a fast winding number: its error is systematic), and *unexpectedly wrong* when
it is right on most of them and wrong on a few: a method meant to be exact that failed somewhere,
which the report names loudly.

Each method is judged against its own definition of inside (plots/definitions.py): its line names
that definition, a point where the mesh's definitions disagree (overlapping shells, |w| > 1) is
shown apart and never counts as wrong, and a job on input outside the method's contract is said
to be so, apart from the wrong ones. Standard library only.
"""
import definitions
import fmt
import tables
from metrics import METRICS, pareto_front
from results_io import config_label, is_batch, method_sort_key

# A configuration wrong on at least this share of its checked jobs is approximate by design.
SYSTEMATIC_SHARE = 0.5


def _checked(jobs):
    return [j for j in jobs if j.ok and j.has_accuracy]


def config_accuracy(rs):
    """{(method, params_key): {"checked": n, "wrong": [jobs], "outside": [jobs], "approximate":
    bool, "definition": text}} over the single-thread jobs on regular models: `wrong` the jobs
    beyond the tolerances under the method's own definition, `outside` those beyond them on input
    outside the method's contract (not counted wrong)."""
    out = {}
    for j in _checked(rs.model_jobs()):
        c = out.setdefault((j.method, j.params_key), {"checked": 0, "wrong": [], "outside": [],
                                                       "definition": definitions.definition_text(j)})
        c["checked"] += 1
        if tables.accuracy_problems(j):
            c["outside" if definitions.outside_contract(j) else "wrong"].append(j)
    for c in out.values():
        c["approximate"] = bool(c["wrong"]) and len(c["wrong"]) >= SYSTEMATIC_SHARE * c["checked"]
    return out


def approximate_configs(rs):
    """The (method, params_key) configurations that are approximate by design in this run."""
    return {k for k, c in config_accuracy(rs).items() if c["approximate"]}


def _worst(jobs):
    """Worst errors over jobs: (inside far-wrong rate, distance max error / diagonal)."""
    far = [METRICS["inside_wrong_rate_far"].getter(j) for j in jobs]
    dist = [j.num("accuracy.distance.rel_error.max") for j in jobs]
    far = [v for v in far if v is not None]
    dist = [v for v in dist if v is not None]
    return (max(far) if far else None), (max(dist) if dist else None)


def _worst_text(jobs):
    far, dist = _worst(jobs)
    parts = []
    if far:
        parts.append(f"up to {fmt.sci(far)} of inside answers wrong far from the surface")
    if dist:
        parts.append(f"distance error up to {fmt.sci(dist)} of the diagonal")
    return "; ".join(parts) or "wrong signs or non-finite answers"


def _definition_label(m, cfgs):
    """"cgal_aabb (ray parity)"; a method whose configurations differ names each one's; results
    made before declarations name none, as then."""
    texts = {c["definition"] for c in cfgs.values()}
    if texts == {definitions.RULE_WORDS["undeclared"]}:
        return m
    if len(texts) == 1:
        return f"{m} ({texts.pop()})"
    return f"{m} (" + "; ".join(f"`{k or 'defaults'}`: {c['definition']}"
                               for k, c in sorted(cfgs.items())) + ")"


def _outside_text(m, cfgs):
    jobs = [j for c in cfgs.values() for j in c["outside"]]
    if not jobs:
        return None
    meshes = sorted({f"{j.mesh} ({definitions.contract_problem(j)})" for j in jobs})
    return (f"- {m}: outside its contract ({definitions.contract_text(jobs[0])}) on "
            f"{len(jobs)} job(s), not counted wrong: {', '.join(meshes)}.")


def dependent_lines(rs):
    """One bullet per regular model with points where its definitions of inside disagree: how
    many, where, what each definition says. Never counted wrong for a method that follows its
    own definition."""
    points, counts = definitions.dependent_points(_checked(rs.model_jobs()))
    lines = []
    for mesh in sorted({m for m, _ in counts}):
        n = sum(c for (m, _), c in counts.items() if m == mesh)
        shown = list(points.get(mesh, {}).values())[:3]
        where = "; ".join(f"at {definitions.point_text(e)} ({e['kind']} queries): "
                          f"{definitions.says_text(e)}" for e in shown)
        lines.append(f"- {mesh}: {n} definition-dependent point(s), where the definitions of "
                     f"inside disagree (each method is judged by its own there, never counted "
                     f"wrong){': ' + where if where else ''}.")
    return lines


def accuracy_lines(rs):
    """One Markdown bullet per method, naming its definition of inside: exact, approximate by
    design (with its worst error), unexpectedly wrong under its own definition (bold, with the
    jobs' count; the appendix lists them), or outside its contract; then the models'
    definition-dependent points."""
    acc = config_accuracy(rs)
    methods = sorted({m for m, _ in acc}, key=method_sort_key)
    lines = []
    for m in methods:
        cfgs = {k: c for (mm, k), c in acc.items() if mm == m}
        label = _definition_label(m, cfgs)
        checked = sum(c["checked"] for c in cfgs.values())
        approx = {k: c for k, c in cfgs.items() if c["approximate"]}
        unexpected = {k: c for k, c in cfgs.items() if c["wrong"] and not c["approximate"]}
        worst_exact = _worst(_checked([j for j in rs.model_jobs() if j.method == m]))[1]
        if unexpected:
            n = sum(len(c["wrong"]) for c in unexpected.values())
            names = ", ".join(f"`{config_label(m + (':' + k if k else ''), k)}`"
                              for k in sorted(unexpected))
            lines.append(f"- **\u26a0 {label}: UNEXPECTED wrong answers in {n} of {checked} checked "
                         f"jobs** ({names}; right on most of its other jobs): "
                         f"{_worst_text([j for c in unexpected.values() for j in c['wrong']])}. "
                         "See the appendix's job-by-job table.")
        if approx:
            wrong = [j for c in approx.values() for j in c["wrong"]]
            names = ", ".join(f"`{k or 'defaults'}`" for k in sorted(approx))
            every = len(approx) == len(cfgs)
            lines.append(f"- {label}: approximate by design ({'every configuration' if every else names}; "
                         f"wrong in {len(wrong)} of {sum(c['checked'] for c in approx.values())} "
                         f"jobs): {_worst_text(wrong)}."
                         + ("" if every else " Its other configurations are exact here."))
        outside = _outside_text(m, cfgs)
        if outside:
            lines.append(outside)
        if not unexpected and not approx:
            exact = checked - sum(len(c["outside"]) for c in cfgs.values())
            lines.append(f"- {label}: exact on "
                         + (f"all {checked}" if exact == checked else f"{exact} of {checked}")
                         + " checked jobs"
                         + (f" (distance error at most {fmt.sci(worst_exact)} of the diagonal)"
                            if worst_exact else "") + ".")
    lines += dependent_lines(rs)
    unchecked = len([j for j in rs.model_jobs() if j.ok and not j.has_accuracy])
    if not methods:
        lines.append("- No ok job on a regular model was checked against the oracle"
                     + (" (stress cases: the stability matrix below)." if rs.stress_meshes else "."))
    if unchecked:
        lines.append(f"- {unchecked} ok job(s) ran without an oracle: not judged.")
    return lines


def _cells(rs):
    """{(mesh, query, kind): [ok single-thread jobs]} on regular models, largest models first."""
    cells = {}
    for j in rs.model_jobs():
        if j.ok and j.qps:
            cells.setdefault((j.mesh, j.query, j.kind), []).append(j)
    order = {m: i for i, m in enumerate(rs.meshes())}
    return dict(sorted(cells.items(), key=lambda kv: (order.get(kv[0][0], 0), kv[0][1] != "inside",
                                                       kv[0][2])))


def _exact(j):
    return j.has_accuracy and not tables.accuracy_problems(j)


def headline_table(rs):
    """(header, rows): per model, query and query path, the fastest exact configuration (of any
    method; batch rows of Python methods left out: one call per query set is no per-query rate),
    the EBP-Octree's fastest exact configuration, and its ratio to the fastest exact
    configuration of any other method (above 1x the EBP-Octree is faster)."""
    header = ["Model", "Triangles", "Query", "Path", "Fastest exact", "Rate",
              "EBP-Octree (fastest exact)", "EBP rate", "EBP ÷ best other exact",
              "Faster but approximate"]
    rows = []
    for (mesh, query, kind), jobs in _cells(rs).items():
        per_query = [j for j in jobs if not is_batch(j.params_key)]
        exact = sorted([j for j in per_query if _exact(j)], key=lambda j: -j.qps)
        if not exact:
            continue
        best = exact[0]
        star = next((j for j in exact if j.method == tables.STAR), None)
        other = next((j for j in exact if j.method != tables.STAR), None)
        ratio = star.qps / other.qps if star and other else None
        faster_approx = sorted([j for j in per_query if j.has_accuracy and not _exact(j)
                                and j.qps > best.qps], key=lambda j: -j.qps)
        rows.append([mesh, fmt.count(rs.mesh_triangles(mesh)), query, kind,
                     config_label(best.config, best.params_key), fmt.hz(best.qps),
                     star.config if star else "– (none exact)", fmt.hz(star.qps) if star else "–",
                     (f"{fmt.ratio(ratio)} vs {other.config}" if ratio else "–"),
                     (f"{faster_approx[0].config} {fmt.hz(faster_approx[0].qps)}"
                      if faster_approx else "–")])
    return header, rows


NOTE = ("Exact = checked against the oracle and within the report's tolerances in this job. "
        "Rates are median queries per second, one thread. Every configuration run counts "
        "(sweeps and path-coherent variants included); Python batch rows ([batch]: one call per "
        "query set) are left out of this table. The ratio divides the EBP-Octree's fastest exact "
        "rate by the fastest exact rate of any other method: above 1× the EBP-Octree is faster.")


def open_scan_table(rs):
    """(header, rows): on open scans, where the generalized winding number is the one definition
    of inside, the methods that compute it (judged against it, within their contract), speed
    against accuracy: per scan and query path, each configuration's rate and its wrong-answer
    rate away from the surface, the Pareto-optimal ones marked. Methods for closed input are
    outside their contract there (the stability matrix shows them)."""
    header = ["Open scan", "Path", "Method (definition)", "Rate", "Wrong far from the surface",
              "Pareto-optimal"]
    groups = {}
    for j in rs.jobs:
        if (j.ok and j.has_accuracy and j.query == "inside" and j.threads == 1
                and definitions.judged_against(j) == "generalized_winding_number"
                and j.get("accuracy.definitions") == ["generalized_winding_number"]
                and not definitions.outside_contract(j) and j.qps):
            groups.setdefault((j.mesh, j.kind), []).append(j)
    rows = []
    for (mesh, kind), jobs in sorted(groups.items()):
        points = [(METRICS["inside_wrong_rate_far"].getter(j) or 0.0, j.qps, j.id) for j in jobs]
        front = {p[2] for p in pareto_front(points, "lower", "higher")}
        for j in sorted(jobs, key=lambda j: -j.qps):
            rows.append([mesh, kind, f"{config_label(j.config, j.params_key)} "
                         f"({definitions.definition_text(j)})", fmt.hz(j.qps),
                         fmt.sci(METRICS["inside_wrong_rate_far"].getter(j) or 0.0),
                         "yes" if j.id in front else ""])
    return header, rows


OPEN_SCAN_NOTE = ("On an open scan only the generalized winding number defines inside (the oracle's: "
                  "an exact integer part and a double-precision sum over the boundary edges, inside "
                  "iff w > 1/2): the methods that compute it, exactly or approximately, are rated on "
                  "it. Rates are median queries per second, one thread; Pareto-optimal: no other "
                  "row of the scan and path is both faster and at least as accurate.")
