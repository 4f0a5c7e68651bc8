"""The stability matrix: how each method configuration copes with each stress case.

One aggregation for every reader: `tools/stability_matrix.py` (stability_matrix.csv and .md, what
`make stability` writes), the report's stability.csv and .md and the matrix in report.md
(plots/report.py), and the report's chart (plots/charts.py `stability_matrix`).

What a cell means
-----------------
A cell is one method configuration (the method and its non-default parameters,
`ebp_octree:leaf_factor=8`) on one case (a stress mesh) for one query type (`inside` or
`distance`), and it aggregates every job of that triple: every query kind the suite ran on the
case (random, near, surface, haptic). The question the stability suite asks is "does this method
cope with this mesh"; a method that copes with uniform points but not with points on the surface
does not. Inside and distance stay apart: they fail differently (on an open scan, inside has no
well-defined answer while distance still has one), and a method may support only one of them.

- `status`: the worst of its jobs' statuses in SEVERITY order, where an `ok` job with an oracle
  is judged against its method's own definition of inside (plots/definitions.py) and counts as
  - `ok_wrong` when its answers break the report's accuracy tolerances under that definition
    (tables.accuracy_problems: a wrong inside answer away from the surface, a distance error
    above 1e-5 of the diagonal, a wrong sign, a non-finite distance) on input within its
    contract: a failure;
  - `outside_contract` when the mesh is input the method does not promise to handle (an open
    scan for a ray-parity method, a flipped patch for one built for oriented meshes), whatever it
    answered: what it answered is shown beside it, never as a failure;
  - `definition_dependent` when it is right under its own definition and the mesh has points
    where the definitions disagree (overlapping shells, an inverted mesh): how many is shown;
  - `ok` otherwise, and `unchecked` when it ran without an oracle;
  any status the harness does not define counts as `error`. `missing`: the suite ran no such job.
- `jobs`, `jobs_ok` (status `ok`, whatever their accuracy), `statuses`: each status the jobs
  recorded with its count, worst first (`timeout:1 ok:2`).
- Accuracy, over the `ok` jobs that have an oracle (`accuracy_jobs` of them), each the worst over
  them: inside: the wrong-answer rate over all points (`inside_wrong_rate_max`) and over the
  points farther than 1e-6 of the diagonal from the surface (`inside_wrong_rate_far_max`), and the
  largest wrong count; distance: the largest absolute and relative (to the mesh diagonal) error,
  the largest relative p99, the sign errors and non-finite answers (sums over the jobs), the
  largest p99 contact-normal error in degrees and the lowest closest-triangle agreement. Blank
  where no job measured it.
- `message`: the distinct messages of its jobs that did not finish ok.

The headline number of a cell, the one on the chart and in the Markdown, is the inside error rate
away from the surface (points within 1e-6 of the diagonal, all the `surface` kind's among them,
have no well-defined side: the rate over all points mostly measures how a method breaks ties
there) or the worst relative distance error. The oracle is exact on closed meshes and the
generalized winding number (inside = |w| > 1/2) on open or broken ones (docs/results.md).

Cases are the result set's stress meshes (results_io.ResultSet.stress_meshes); open scans
(`*_open`) come first. Standard library only, like the modules it uses: the command line needs
no plotting library.
"""
import csv
import io
import os
from collections import Counter

import definitions
import fmt
import tables
from metrics import METRICS
from results_io import KNOWN_STATUSES, method_sort_key, write_atomic

QUERIES = ("inside", "distance")

# Worse statuses win when several jobs fall in one cell. `unsupported` is the mildest: a method
# that says it does not answer is honest; `rejected_input` is below the wrong answers because
# refusing a mesh (the empty one must be refused) at least says so.
# A definition-dependent cell is right (by the method's own definition); a cell outside the
# contract is not a failure either, but says less than an ok one.
SEVERITY = ["missing", "not_run", "unsupported", "ok", "definition_dependent", "unchecked", "outside_contract",
            "rejected_input", "ok_wrong", "error", "timeout", "oom", "crash"]

CSV_COLUMNS = [
    "query", "method", "mesh", "status", "jobs", "jobs_ok", "statuses",
    "inside_wrong_rate_max", "inside_wrong_rate_far_max", "inside_wrong_max",
    "dist_abs_err_max", "dist_rel_err_max", "dist_rel_err_p99_max", "sign_wrong", "non_finite",
    "normal_err_p99_deg_max", "triangle_agreement_min", "accuracy_jobs", "message",
    "definition", "judged_against", "definition_dependent_max", "definition_dependent_rate_max",
    "contract_problem",
]


def recorded_status(status):
    """The SEVERITY entry of a status as a result records it: any the harness does not define
    is an error."""
    return status if status in KNOWN_STATUSES else "error"


def job_status(job):
    """A job's status as the matrix sees it: ok jobs split into ok / ok_wrong / unchecked."""
    if not job.ok:
        return recorded_status(job.status)
    if not job.has_accuracy:
        return "unchecked"
    if definitions.outside_contract(job):
        return "outside_contract"
    if tables.accuracy_problems(job):
        return "ok_wrong"
    return "definition_dependent" if definitions.dependent_count(job) else "ok"


def _dependent_rate(job):
    n = job.n_queries
    return definitions.dependent_count(job) / n if n else None


def worst(statuses):
    return max(statuses, key=SEVERITY.index, default="missing")


def _worst_value(values, pick=max):
    vals = [v for v in values if v is not None]
    return pick(vals) if vals else None


def _total(values):
    vals = [v for v in values if v is not None]
    return int(sum(vals)) if vals else None


def aggregate(jobs):
    """One cell (a dict with the CSV's columns but query, method and mesh) from its jobs."""
    seen = Counter(job_status(j) for j in jobs)
    # Worst first; the jobs' own words for statuses the harness does not define.
    recorded = Counter(j.status for j in jobs)
    order = sorted(recorded, key=lambda s: -SEVERITY.index(recorded_status(s)))
    ok = [j for j in jobs if j.ok]
    acc = [j for j in ok if j.has_accuracy]
    inside = [j for j in acc if isinstance(j.get("accuracy.inside"), dict)]
    dist = [j for j in acc if isinstance(j.get("accuracy.distance"), dict)]
    return {
        "status": worst(seen),
        "status_jobs": seen[worst(seen)] if jobs else 0,
        "jobs": len(jobs),
        "jobs_ok": len(ok),
        "statuses": " ".join(f"{s}:{recorded[s]}" for s in order),
        "inside_wrong_rate_max": _worst_value(METRICS["inside_wrong_rate"].getter(j)
                                              for j in inside),
        "inside_wrong_rate_far_max": _worst_value(METRICS["inside_wrong_rate_far"].getter(j)
                                                  for j in inside),
        "inside_wrong_max": _worst_value(j.num("accuracy.inside.wrong") for j in inside),
        "dist_abs_err_max": _worst_value(j.num("accuracy.distance.abs_error.max") for j in dist),
        "dist_rel_err_max": _worst_value(METRICS["dist_rel_err_max"].getter(j) for j in dist),
        "dist_rel_err_p99_max": _worst_value(METRICS["dist_rel_err_p99"].getter(j)
                                             for j in dist),
        "sign_wrong": _total(j.num("accuracy.distance.sign_wrong") or 0 for j in dist),
        "non_finite": _total(j.num("accuracy.distance.non_finite") or 0 for j in dist),
        "normal_err_p99_deg_max": _worst_value(METRICS["normal_err_p99"].getter(j) for j in dist),
        "triangle_agreement_min": _worst_value(
            (j.num("accuracy.distance.triangle_agreement") for j in dist), pick=min),
        "accuracy_jobs": len(acc),
        "message": "; ".join(sorted({j.message for j in jobs if not j.ok and j.message})),
        "definition": "; ".join(sorted({definitions.definition_text(j) for j in jobs})),
        "judged_against": " ".join(sorted({definitions.judged_against(j) for j in acc})),
        "definition_dependent_max": _worst_value(definitions.dependent_count(j) for j in acc),
        "definition_dependent_rate_max": _worst_value(_dependent_rate(j) for j in acc),
        "contract_problem": "; ".join(sorted({definitions.contract_problem(j) for j in acc
                                              if definitions.outside_contract(j)})),
    }


def sort_cases(meshes):
    """Open scans (`*_open`, the real-world cases) first, then by name."""
    return sorted(meshes, key=lambda c: (not c.endswith("_open"), c))


def cases(rs):
    """The cases of a result set's matrix: its stress meshes."""
    return sort_cases(rs.stress_meshes)


def matrix(rs, meshes=None):
    """{query: (configs, meshes, {(config, mesh): cell})} for the queries the suite ran on the
    cases (default: `cases(rs)`); every (config, mesh) pair has a cell, `missing` when no job."""
    meshes = cases(rs) if meshes is None else list(meshes)
    wanted = set(meshes)
    on_cases = [j for j in rs.jobs if j.mesh in wanted]
    out = {}
    for query in sorted({j.query for j in on_cases},
                        key=lambda q: (QUERIES.index(q) if q in QUERIES else len(QUERIES), q)):
        js = [j for j in on_cases if j.query == query]
        configs = sorted({j.config for j in js}, key=lambda c: (method_sort_key(c.split(":")[0]),
                                                                 c))
        by_cell = {}
        for j in js:
            by_cell.setdefault((j.config, j.mesh), []).append(j)
        cells = {(c, m): aggregate(by_cell.get((c, m), [])) for c in configs for m in meshes}
        out[query] = (configs, meshes, cells)
    return out


# ---------------------------------------------------------------------------------------------
# What a cell says
# ---------------------------------------------------------------------------------------------
def headline(query, cell):
    """The cell's one number: the far-from-surface inside error rate (the overall rate where a
    result has no far count) or the worst relative distance error; None when not measured."""
    if query == "inside":
        far = cell["inside_wrong_rate_far_max"]
        return far if far is not None else cell["inside_wrong_rate_max"]
    return cell["dist_rel_err_max"]


_SHORT = {"unsupported": "n/a", "rejected_input": "rejected", "unchecked": "ok?", "missing": "",
          "timeout": "timeout", "crash": "CRASH", "oom": "OOM", "error": "error"}
# Statuses whose cells still show their numbers: the method ran and was measured.
MEASURED = ("ok", "ok_wrong", "definition_dependent", "outside_contract")


def short_text(query, cell):
    """A few characters for a chart cell: the headline number of ok cells, else the status."""
    st = cell["status"]
    if st in MEASURED:
        v = headline(query, cell)
        text = fmt.sci(v, 1) if v is not None else "ok"
        return {"outside_contract": "out: ", "definition_dependent": "def: "}.get(st, "") + text
    return _SHORT.get(st, st)


def _pct(v):
    return "0" if v == 0 else f"{100 * v:.3g}%"


def _num(v):
    return "0" if v == 0 else f"{v:.2g}"


def md_text(query, cell):
    """A Markdown cell: the status (bold unless ok, with how many jobs had it), then the numbers
    of the ok jobs: `in` = inside error rate away from the surface (`in(all)` where only the
    overall rate is known), `d` = worst distance error / diagonal, sign errors, non-finite."""
    st = cell["status"]
    if st == "missing":
        return "—"
    text = {"ok": "ok", "unchecked": "ok (no oracle)", "ok_wrong": "**wrong**",
            "definition_dependent": "ok, definition-dependent",
            "outside_contract": "outside contract"}.get(st, f"**{st}**")
    if st != "ok" and cell["jobs"] > 1:
        text += f" {cell['status_jobs']}/{cell['jobs']}"
    parts = []
    if cell["definition_dependent_rate_max"]:
        parts.append("def-dep " + _pct(cell["definition_dependent_rate_max"]))
    if query == "inside":
        if cell["inside_wrong_rate_far_max"] is not None:
            parts.append("in " + _pct(cell["inside_wrong_rate_far_max"]))
        elif cell["inside_wrong_rate_max"] is not None:
            parts.append("in(all) " + _pct(cell["inside_wrong_rate_max"]))
    else:
        if cell["dist_rel_err_max"] is not None:
            parts.append("d " + _num(cell["dist_rel_err_max"]))
        if cell["sign_wrong"]:
            parts.append(f"sign {cell['sign_wrong']}")
        if cell["non_finite"]:
            parts.append(f"NaN {cell['non_finite']}")
    return " · ".join([text] + parts)


# ---------------------------------------------------------------------------------------------
# Outputs
# ---------------------------------------------------------------------------------------------
def rows(m):
    """The CSV rows (lists in CSV_COLUMNS order; None for blanks) of the cells that have jobs."""
    out = []
    for query, (configs, meshes, cells) in m.items():
        for c in configs:
            for mesh in meshes:
                cell = cells[(c, mesh)]
                if cell["jobs"]:
                    row = dict(cell, query=query, method=c, mesh=mesh)
                    out.append([row[k] for k in CSV_COLUMNS])
    return out


def to_csv(m):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    w.writerows([["" if v is None else v for v in r] for r in rows(m)])
    return buf.getvalue()


LEGEND = ("Each cell: one method configuration on one case for one query type, over every query "
          "kind the suite ran there, judged against the method's own definition of inside (ray "
          "parity, the winding number, the generalized winding number: `bvhbench methods` lists "
          "each method's). The status is the worst of its jobs' (`wrong` = finished ok but beyond "
          "the accuracy tolerances under its own definition, on input within its contract; "
          "`outside contract` = run on input it does not promise to handle, its answers shown "
          "against the oracle's definition but not counted as a failure; `definition-dependent` = "
          "right under its own definition on a mesh where the definitions disagree, `def-dep` "
          "saying on how many of the points; a count says how many of the cell's jobs had it), "
          "then, over the ok jobs: `in` = worst inside error rate among points farther than 1e-6 "
          "of the diagonal from the surface (the CSV also has the rate over all points), `d` = "
          "worst distance error / mesh diagonal, `sign` = distances with the wrong sign, `NaN` = "
          "non-finite distances. Where a method's definition is not defined on the mesh (ray "
          "parity on an open scan) it is judged against the oracle's default: the integer winding "
          "number (nonzero) on closed meshes, the generalized winding number (|w| > 1/2) on open "
          "or broken ones. `—` = not run.")


def matrix_md(m):
    """The matrix as Markdown: one table per query type, configurations x cases."""
    parts = []
    for query, (configs, meshes, cells) in m.items():
        header = [f"{query} \\ mesh"] + meshes
        body = [[c] + [md_text(query, cells[(c, mesh)]) for mesh in meshes] for c in configs]
        parts.append(tables.render_md(header, body))
    return "\n".join(parts)


def _flat_md(m):
    """Every cell with jobs as one row, with its messages."""
    header = ["query", "method", "mesh", "status", "statuses", "inside_wrong_rate_far_max",
              "dist_rel_err_max", "message"]
    idx = [CSV_COLUMNS.index(h) for h in header]
    body = []
    for r in rows(m):
        cells = [r[i] for i in idx]
        cells[5], cells[6] = fmt.sci(cells[5]), fmt.sci(cells[6])
        body.append(cells)
    return tables.render_md(header, body)


def to_md(rs, m):
    n_cases = len(next(iter(m.values()))[1]) if m else 0
    n_cfg = len({c for configs, _, _ in m.values() for c in configs})
    n_jobs = sum(cell["jobs"] for _, _, cells in m.values() for cell in cells.values())
    md = [f"# Stability matrix: `{rs.name}`", "", tables.context_line(rs), "",
          f"{n_jobs} job(s) on {n_cases} case(s), {n_cfg} method configuration(s). " + LEGEND,
          ""]
    if rs.unreadable:
        md += [f"{len(rs.unreadable)} result file(s) could not be read: "
               + ", ".join(f"`{n}` ({e[:120]})" for n, e in rs.unreadable[:10]), ""]
    md += [matrix_md(m), "## Every cell", "", _flat_md(m)]
    return "\n".join(md)


def write(rs, out_dir, csv_name, md_name, meshes=None):
    """Writes the matrix of `rs` (over `meshes`, default its stress cases) as CSV and Markdown
    into out_dir, atomically; returns the two paths."""
    m = matrix(rs, meshes)
    os.makedirs(out_dir, exist_ok=True)
    csv_path, md_path = os.path.join(out_dir, csv_name), os.path.join(out_dir, md_name)
    write_atomic(csv_path, to_csv(m))
    write_atomic(md_path, to_md(rs, m))
    return csv_path, md_path
