"""Tables of the report: run context, the paper's tables, non-ok jobs and accuracy warnings
(the stability matrix is plots/stability.py). Each table is built once as (header, rows) and
rendered to Markdown, LaTeX or CSV by the `render_*` functions, so the formats never disagree.
"""
import csv
import io

import fmt
from metrics import METRICS
from results_io import (config_label, is_coherent, median, method_sort_key, representative_configs,
                        shown_configs)

# Accuracy tolerances of the report's accuracy lines and its job-by-job appendix (plots/headline.py).
DIST_REL_ERR_TOL = 1e-5      # distance error above 1e-5 of the mesh diagonal is a wrong answer
INSIDE_FAR_WRONG_TOL = 0     # any wrong inside answer far from the surface is a wrong answer

# The figures published by Aguilera, Melero & Feito, CAD 77 (2016), measured on 2015 hardware.
PAPER_REFERENCE = {
    "citation": "Aguilera, Melero, Feito: Out-of-core real-time haptic interaction on very "
                "large models, Computer-Aided Design 77 (2016) 98-106",
    "polygons": "25M-30M",
    "min_polygons": 25e6,        # the scale the published rates are claimed for
    "levels": "11",
    "pis_random_hz": 2.5e3,
    "pis_haptic_hz": 32e3,
    "dist_haptic_hz": 1e6,
    # "around 1 MHz in classic haptic interaction over the surface": the probe in contact, which
    # the `contact` query kind replays (the haptic path's contact phases alone).
    "dist_contact_hz": 1e6,
}
STAR = "ebp_octree"


# ---------------------------------------------------------------------------------------------
# Rendering
# ---------------------------------------------------------------------------------------------
def _md_cell(x):
    return str(x).replace("|", "\\|").replace("\n", " ")


def render_md(header, rows):
    lines = ["| " + " | ".join(_md_cell(h) for h in header) + " |",
             "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(_md_cell(c) for c in r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


_TEX_ESCAPES = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#",
                "_": r"\_", "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}",
                "^": r"\textasciicircum{}", "×": r"$\times$", "µ": r"$\mu$", "–": "--",
                "≥": r"$\geq$", "÷": r"$\div$", "★": r"$\star$", "≈": r"$\approx$",
                "`": ""}


def tex_escape(s):
    return "".join(_TEX_ESCAPES.get(ch, ch) for ch in str(s))


def render_tex(header, rows, caption, label, bold_rows=(), left_cols=3):
    """A booktabs table (needs \\usepackage{booktabs}); bold_rows are row indices to embolden;
    the first left_cols columns are text (left-aligned), the rest numbers."""
    out = [r"\begin{table}[htbp]", r"\centering", r"\footnotesize",
           r"\begin{tabular}{" + "l" * left_cols + "r" * (len(header) - left_cols) + "}",
           r"\toprule",
           " & ".join(tex_escape(h) for h in header) + r" \\", r"\midrule"]
    for i, r in enumerate(rows):
        cells = [tex_escape(c) for c in r]
        if i in bold_rows:
            cells = [r"\textbf{" + c + "}" if c else c for c in cells]
        out.append(" & ".join(cells) + r" \\")
    out += [r"\bottomrule", r"\end{tabular}", r"\caption{" + tex_escape(caption) + "}",
            r"\label{" + label + "}", r"\end{table}"]
    return "\n".join(out) + "\n"


def render_csv(header, rows):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()


# ---------------------------------------------------------------------------------------------
# Context: which machine, which run
# ---------------------------------------------------------------------------------------------
def _dates(c):
    a, b = c["date_first"], c["date_last"]
    if not a:
        return "date unknown"
    if a == b:
        return a
    # Same day: give the second time only ('2026-11-22T07:20:12Z to 07:27:20Z').
    if a[:10] == b[:10] and "T" in b:
        return f"{a} to {b.split('T', 1)[1]}"
    return f"{a} to {b}"


def _commits(c, limit=3):
    short = [x[:10] for x in c["commits"]]
    if not short:
        s = "commit unknown"
    elif len(short) == 1:
        s = f"commit {short[0]}"
    else:
        s = (f"{len(short)} commits ({', '.join(short[:limit])}"
             + (", ..." if len(short) > limit else "") + ")")
    return s + (" (dirty)" if c["dirty"] else "")


def context_line(rs):
    """One line naming the machine(s) and run(s) behind the results."""
    ctxs = rs.contexts()
    parts = []
    for c in ctxs:
        s = (f"machine {c['host'] or '?'} ({c['cpu_model'] or 'unknown CPU'}, "
             f"{c['cores'] or '?'} cores"
             + (f", {c['compiler']} {c['build_type']}".rstrip() if c["compiler"] else "")
             + f"); run {_dates(c)}, {_commits(c)}")
        if len(ctxs) > 1:
            s += f" [{c['jobs']} jobs]"
        parts.append(s)
    return f"Suite `{rs.name}`: " + "; ".join(parts) + "."


def context_table(rs):
    header = ["host", "CPU", "cores", "compiler", "build type", "bvhbench", "dates",
              "git commits", "dirty", "jobs"]
    rows = [[c["host"], c["cpu_model"], c["cores"], c["compiler"], c["build_type"],
             c["bvhbench_version"], _dates(c), ", ".join(c["commits"]),
             "yes" if c["dirty"] else "no", c["jobs"]]
            for c in rs.contexts()]
    return header, rows


# ---------------------------------------------------------------------------------------------
# The paper's tables
# ---------------------------------------------------------------------------------------------
def _pick(jobs, query, kind):
    """Median throughput of the ok jobs matching (query, kind); None if none."""
    return median(j.qps for j in jobs if j.ok and j.query == query and j.kind == kind)


def _inaccurate(jobs, query, kind):
    return any(accuracy_problems(j) for j in jobs if j.query == query and j.kind == kind)


WRONG_MARK = "(!)"   # beside a rate whose answers were wrong; explained under the table


def _status_note(jobs, query, kind):
    """'timeout' etc. when the only jobs for this cell failed."""
    st = sorted({j.status for j in jobs if j.query == query and j.kind == kind and not j.ok})
    return "/".join(st) if st else None


# The paper's measures, each a query on a query kind (its published figures, PAPER_REFERENCE):
# named here because they are the paper's, not a listing of the kinds (that is the runner's,
# registry.query_kinds()).
RATE_COLUMNS = [("pis_random", "inside", "random"), ("pis_haptic", "inside", "haptic"),
                ("dist_haptic", "distance", "haptic"), ("dist_contact", "distance", "contact")]


def job_hosts(jobs):
    """The hosts the jobs ran on, sorted ('' for a result that names none)."""
    return sorted({j.get("context.host") or "" for j in jobs})


def paper_rows(rs):
    """Per model and method: the figures of the paper's tables, as numbers (None = absent).
    When the jobs ran on several hosts (a suite on a cluster), per host, model and method: a
    rate is a median over one machine only, and each row names its "host"."""
    jobs = rs.model_jobs()
    configs = shown_configs(jobs)
    hosts = job_hosts(jobs)
    out = []
    for host, mesh in [(h, m) for h in hosts for m in rs.meshes(jobs)]:
        on_mesh = [j for j in jobs if j.mesh == mesh
                   and (len(hosts) == 1 or (j.get("context.host") or "") == host)]
        for method, key in configs:
            js = [j for j in on_mesh if j.method == method and j.params_key == key]
            if not js:
                continue
            ok = [j for j in js if j.ok]
            levels = next((j.get("structure.levels") for j in ok
                           if j.get("structure.levels") is not None), None)
            if levels is None:
                levels = next((j.get("structure.max_depth") for j in ok
                               if j.get("structure.max_depth") is not None), None)
            row = {
                "host": host, "mesh": mesh, "triangles": rs.mesh_triangles(mesh), "method": method,
                "config": config_label(js[0].config, key), "coherent": is_coherent(key), "levels": levels,
                "build_s": median(j.build_seconds for j in ok),
                "structure_bytes": median(j.structure_bytes for j in ok),
                "file_bytes": median(j.file_bytes for j in ok),
                **{k: _pick(js, q, kd) for k, q, kd in RATE_COLUMNS},
                "notes": {k: _status_note(js, q, kd) for k, q, kd in RATE_COLUMNS},
                "wrong": {k: _inaccurate(js, q, kd) for k, q, kd in RATE_COLUMNS},
            }
            out.append(row)
    return out


def _rate_cell(row, key):
    v = row[key]
    if v is not None:
        return fmt.hz(v) + (" " + WRONG_MARK if row["wrong"][key] else "")
    return row["notes"].get(key) or "–"


def _ratio(a, b):
    return a / b if a and b else None


def paper_tables(rs, reproduced=None):
    """(main, ratios): two (header, rows, bold_row_indices) tables. When the jobs ran on several
    hosts, both begin with a "Host" column and a ratio pairs the EBP-Octree and a peer of one
    host only (ratios are never taken across machines). reproduced: {rate column key
    (RATE_COLUMNS): verdict text} for a row under the published figures (reproduction.py)."""
    rows = paper_rows(rs)
    by_host = len({r["host"] for r in rows}) > 1
    host_cell = (lambda r: [r["host"] or "?"]) if by_host else (lambda r: [])
    main_h = (["Host"] if by_host else []) + [
        "Model", "Polygons", "Method", "Octree levels", "Build", "Structure (memory)",
        "Structure (disk)", "PiS random", "PiS haptic", "Distance haptic", "Distance contact"]
    main, bold = [], []
    for r in rows:
        if r["method"] == STAR:
            bold.append(len(main))
        main.append(host_cell(r) + [r["mesh"], fmt.count(r["triangles"]), r["config"],
                     r["levels"] if r["levels"] is not None else "–",
                     fmt.seconds(r["build_s"]), fmt.nbytes(r["structure_bytes"]),
                     fmt.nbytes(r["file_bytes"]), _rate_cell(r, "pis_random"),
                     _rate_cell(r, "pis_haptic"), _rate_cell(r, "dist_haptic"),
                     _rate_cell(r, "dist_contact")])
    p = PAPER_REFERENCE
    main.append((["–"] if by_host else []) + [
        "Paper (2016, 2015 hardware)", p["polygons"], "EBP-Octree (published)",
        p["levels"], "–", "–", "–", fmt.hz(p["pis_random_hz"]),
        fmt.hz(p["pis_haptic_hz"]), "≈" + fmt.hz(p["dist_haptic_hz"]), "≈" + fmt.hz(p["dist_contact_hz"])])
    if reproduced:
        main.append((["–"] if by_host else []) + [
            "Reproduced by this run?", f"{fmt.count(p['min_polygons'])}+", "EBP-Octree",
            "–", "–", "–", "–"] + [reproduced.get(k, "–") for k, _, _ in RATE_COLUMNS])

    ratio_h = (["Host"] if by_host else []) + [
        "Model", "Polygons", "Peer", "PiS random: EBP/peer", "PiS haptic: EBP/peer",
        "Distance haptic: EBP/peer", "Distance contact: EBP/peer", "Build time: peer/EBP",
        "Memory: peer/EBP"]
    ratios = []
    by_mesh = {}
    for r in rows:
        by_mesh.setdefault((r["host"], r["mesh"]), []).append(r)
    for (_, mesh), rs_ in by_mesh.items():
        stars = [r for r in rs_ if r["method"] == STAR]
        if not stars:
            continue
        for r in rs_:
            if r["method"] == STAR:   # its own variants are not peers
                continue
            # A path-coherent peer is compared with the EBP-Octree's coherent variant when the
            # suite ran one (same coherence on both sides), otherwise with its default.
            star = next((s for s in stars if s["coherent"] == r["coherent"]), stars[0])
            ratios.append(host_cell(r) + [mesh, fmt.count(r["triangles"]), r["config"],
                           fmt.ratio(_ratio(star["pis_random"], r["pis_random"])),
                           fmt.ratio(_ratio(star["pis_haptic"], r["pis_haptic"])),
                           fmt.ratio(_ratio(star["dist_haptic"], r["dist_haptic"])),
                           fmt.ratio(_ratio(star["dist_contact"], r["dist_contact"])),
                           fmt.ratio(_ratio(r["build_s"], star["build_s"])),
                           fmt.ratio(_ratio(r["structure_bytes"], star["structure_bytes"]))])
    return (main_h, main, bold), (ratio_h, ratios, [])


def paper_notes(rs):
    reps = representative_configs(rs.model_jobs())
    swept = sorted(m for m in reps if len({j.params_key for j in rs.model_jobs()
                                          if j.method == m}) > 1)
    note = ("Rates are median queries per second over repetitions, single thread. "
            "PiS = point-in-solid (`inside`). Ratios above 1× favour the EBP-Octree: "
            "rates are EBP/peer, build time and memory are peer/EBP; a path-coherent peer "
            "(coherent=true) is compared with the EBP-Octree's coherent variant when it ran. "
            "[batch] marks a Python method answering the whole query set per call "
            "(batch=true): its rate is what a Python caller gets from arrays, not a per-query "
            "latency; the same method without [batch] is called once per query. "
            "A status instead of a rate means that job did not finish ok (see the non-ok table); "
            f"{WRONG_MARK} marks a rate whose answers were wrong (see the report's accuracy lines and appendix). "
            "Published figures: " + PAPER_REFERENCE["citation"] + ": 2.5 kHz random and 32 kHz "
            "haptic-path point-in-solid, about 1 MHz distance on haptic paths over models of "
            "25M+ polygons, on 2015 hardware; they are cited for reference, not measured here.")
    if swept:
        note += (" Methods with a parameter sweep are shown in one configuration: the default "
                 "when it was run, else the one run on most models (" +
                 ", ".join(f"{m}: `{reps[m] or 'defaults'}`" for m in swept) + ").")
    return note


# ---------------------------------------------------------------------------------------------
# Non-ok jobs and accuracy warnings
# ---------------------------------------------------------------------------------------------
def failed_table(rs):
    header = ["Status", "Method", "Mesh", "Query", "Path", "Message", "Job"]
    rows = [[j.status, config_label(j.config, j.params_key), j.mesh, j.query, j.kind, j.message or "(no message)", j.id]
            for j in sorted(rs.failed_jobs, key=lambda j: (j.status, method_sort_key(j.method),
                                                           j.mesh, j.query, j.kind))]
    return header, rows


def accuracy_problems(job):
    """Human-readable reasons why an ok job's answers are wrong (empty list: none)."""
    if not job.ok or not job.has_accuracy:
        return []
    out = []
    far = job.num("accuracy.inside.wrong_far")
    if far is not None and far > INSIDE_FAR_WRONG_TOL:
        rate = METRICS["inside_wrong_rate_far"].getter(job)
        out.append(f"{int(far)} wrong inside answers far from the surface"
                   + (f" (rate {fmt.sci(rate)})" if rate is not None else ""))
    elif far is None:
        wrong = job.num("accuracy.inside.wrong")
        near = job.num("accuracy.inside.wrong_near_surface") or 0
        if wrong is not None and wrong - near > INSIDE_FAR_WRONG_TOL:
            out.append(f"{int(wrong)} wrong inside answers ({int(near)} near the surface)")
    rel = job.num("accuracy.distance.rel_error.max")
    if rel is not None and rel > DIST_REL_ERR_TOL:
        out.append(f"distance error up to {fmt.sci(rel)} of the diagonal "
                   f"(p99 {fmt.sci(job.num('accuracy.distance.rel_error.p99'))}, "
                   f"tolerance {DIST_REL_ERR_TOL:g})")
    sign = job.num("accuracy.distance.sign_wrong")
    if sign:
        out.append(f"{int(sign)} distances with the wrong sign")
    # Kept out of the error statistics by the harness, so they must be named here.
    non_finite = job.num("accuracy.distance.non_finite")
    if non_finite:
        out.append(f"{int(non_finite)} non-finite distances (NaN or infinite)")
    return out


def accuracy_warnings(rs):
    header = ["Method", "Mesh", "Query", "Path", "Problem", "Job"]
    rows = []
    for j in sorted(rs.ok_jobs, key=lambda j: (method_sort_key(j.method), j.params_key, j.mesh,
                                               j.query, j.kind)):
        probs = accuracy_problems(j)
        if probs:
            rows.append([j.config, j.mesh, j.query, j.kind, "; ".join(probs), j.id])
    unchecked = [j for j in rs.ok_jobs if not j.has_accuracy]
    return header, rows, unchecked
