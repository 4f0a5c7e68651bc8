#!/usr/bin/env python3
"""Build the report of one result set.

    python plots/report.py results/NAME [--out DIR] [--strict]

Reads results/NAME/runs/*.json (and cross-checks summary.csv); writes into results/NAME/report/
(or --out): one PNG and one SVG per chart (see charts.CHARTS), report.md showing them and
report.html, the same report as one self-contained page (charts inline, tables that sort and
filter; html_report.py), the
paper's tables as paper_table.md and paper_table.tex, and, for suites with stress meshes,
stability.csv and stability.md.

Exit codes: 0 report written; 1 some chart failed to draw (report written without it);
2 bad usage or no results to report on.
"""
import argparse
import re
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import charts  # noqa: E402
import definitions  # noqa: E402
import headline  # noqa: E402
import html_report  # noqa: E402
import reproduction  # noqa: E402
import stability  # noqa: E402
import tables  # noqa: E402
from results_io import ReportError, load, write_atomic  # noqa: E402


def draw_charts(rs, out, strict):
    """{name: ("ok", files) | ("nodata", reason) | ("failed", error)}"""
    done = {}
    for name, chart in charts.CHARTS.items():
        try:
            fig = chart.func(rs)
        except charts.NoData as e:
            done[name] = ("nodata", str(e))
            continue
        except Exception as e:  # one broken chart must not cost the whole report
            if strict:
                raise
            traceback.print_exc()
            done[name] = ("failed", f"{type(e).__name__}: {e}")
            continue
        files = []
        for ext in ("png", "svg"):
            f = f"{name}.{ext}"
            fig.savefig(os.path.join(out, f), bbox_inches="tight")
            files.append(f)
        plt.close(fig)
        done[name] = ("ok", files)
    return done


# The charts on the report's first screen, beside the headline table: speed against accuracy.
FIRST_CHARTS = ("pareto_inside_wrong_rate", "pareto_distance_rel_err_p99")


def _chart_md(name, drawn, rs):
    """A chart's section; none for a chart with nothing to draw (not_drawn_md lists those)."""
    chart = charts.CHARTS[name]
    state, detail = drawn[name]
    if state == "nodata":
        return []
    md = [f"## {chart.title}", ""]
    if state == "ok":
        png, svg = detail
        md += [f"![{chart.title}]({png})", "", chart.caption + f" ([SVG]({svg}))", ""]
    else:
        md += [f"**Chart failed to draw:** `{detail}`", ""]
    if name == "stability_matrix" and state == "ok":
        md += [tables.context_line(rs), "", stability.LEGEND, "",
               stability.matrix_md(stability.matrix(rs)),
               "Also as [stability.csv](stability.csv) and [stability.md](stability.md).", ""]
    return md


def not_drawn_md(drawn):
    """One list, at the end, of the charts left out for having nothing to draw, with why."""
    missing = [(charts.CHARTS[n].title, detail) for n, (state, detail) in drawn.items()
               if state == "nodata"]
    if not missing:
        return []
    return (["## Charts with nothing to show", ""]
            + [f"- {title}: _Not drawn: {detail}._" for title, detail in missing] + [""])


def _accuracy_md(rs):
    """Each method's accuracy line, the models' definition-dependent points and the tolerances;
    nothing when no job on a regular model was checked (a stability run: its matrix says it)."""
    lines = headline.accuracy_lines(rs)
    if not headline.config_accuracy(rs) and rs.stress_meshes:
        return []
    return (["## Accuracy, per method", ""] + lines + [""]
            + [f"Each method is judged against its own definition of inside (`bvhbench methods` "
               f"lists them): inside answers wrong by it far from the surface (beyond 1e-6 of "
               f"the diagonal) count as wrong; distances beyond {tables.DIST_REL_ERR_TOL:g} of "
               "the diagonal, with a wrong sign by it or non-finite, too. Points where the "
               "mesh's definitions disagree are counted apart, never wrong. Every job: the "
               "appendix \"Accuracy, job by job\".", ""])


def _matrix_first(rs):
    """A stability run (every mesh a stress case) opens with its matrix: nothing else answers."""
    return (rs.is_stability_suite() and set(rs.meshes()) <= set(rs.stress_meshes)
            and "stability_matrix" in charts.CHARTS)


def _first_screen(rs, drawn, paper_md):
    """What a reader came for: a stability run's matrix; else the fastest exact method per model
    and query with the EBP-Octree's ratio to it, each method's accuracy in a line, the
    speed/accuracy charts and the paper's tables. Sections with nothing to show are left out."""
    md = []
    if _matrix_first(rs):
        md += _chart_md("stability_matrix", drawn, rs)
    h, rows = headline.headline_table(rs)
    if rows:
        md += ["## Fastest exact method per model and query", "",
               tables.render_md(h, rows), headline.NOTE, ""]
    md += _accuracy_md(rs)
    for name in FIRST_CHARTS:
        if name in charts.CHARTS:
            md += _chart_md(name, drawn, rs)
    h, rows = headline.open_scan_table(rs)
    if rows:
        md += ["## Open scans: speed against accuracy (generalized winding number)", "",
               tables.render_md(h, rows), headline.OPEN_SCAN_NOTE, ""]
    if any(j.ok for j in rs.model_jobs()):
        md += ["## The paper's tables", "", paper_md]
    return md


def _appendix_md(rs, ctx, warn_h, warn_rows, unchecked):
    """Every ok job beyond the tolerances under its method's own definition, those run on input
    outside the method's contract apart (not failures), and the jobs without an oracle."""
    if not warn_rows and not unchecked:
        return []
    by_id = {j.id: j for j in rs.ok_jobs}
    outside = [r for r in warn_rows if r[-1] in by_id and definitions.outside_contract(by_id[r[-1]])]
    wrong = [r for r in warn_rows if r not in outside]
    md = ["## Appendix: accuracy, job by job", ""]
    if wrong:
        md += [f"{len(wrong)} job(s) finished `ok` with answers beyond the tolerances "
               f"(inside: wrong far from the surface; distance: error above "
               f"{tables.DIST_REL_ERR_TOL:g} of the diagonal, a wrong sign or a non-finite "
               "answer), each judged against its method's own definition of inside. Their "
               "speed figures are not comparable to exact methods'.", "",
               ctx, "", tables.render_md(warn_h, wrong)]
    if outside:
        md += [f"{len(outside)} job(s) ran on input outside their method's contract (a mesh it "
               "does not promise to handle: the stability matrix says why), judged against the "
               "oracle's definition where the mesh does not define the method's own; not "
               "failures.", "", tables.render_md(warn_h, outside)]
    if unchecked:
        md += [f"Not checked (no oracle): {len(unchecked)} ok job(s): "
               + ", ".join(f"`{j.id}`" for j in unchecked[:20])
               + (" ..." if len(unchecked) > 20 else "") + ".", ""]
    return md


def build_markdown(rs, drawn, paper_md):
    """The report: first what a reader came for (_first_screen), then every other chart and
    table, the job-by-job accuracy table in an appendix. Sections with nothing to show are left
    out (the charts among them are listed at the end, with why)."""
    ctx = tables.context_line(rs)
    warn_h, warn_rows, unchecked = tables.accuracy_warnings(rs)
    failed_h, failed_rows = tables.failed_table(rs)
    n_ok = len(rs.ok_jobs)
    md = [f"# bvhbench report: `{rs.name}`", "",
          ctx, "",
          f"{len(rs.jobs)} jobs: {n_ok} ok, {len(failed_rows)} not ok"
          + (f", {len(warn_rows)} ok jobs with answers beyond the tolerances "
             "(approximate methods and input outside a method's contract among them; see "
             "Accuracy)" if warn_rows else "")
          + (f", {len(unchecked)} ok jobs without an oracle" if unchecked else "") + ".", ""]
    md += _first_screen(rs, drawn, paper_md)
    first = {"stability_matrix"} if _matrix_first(rs) else set()
    for name in charts.CHARTS:
        if name not in FIRST_CHARTS and name not in first:
            md += _chart_md(name, drawn, rs)

    if failed_rows:
        md += ["## Jobs that did not finish ok", "", ctx, "", tables.render_md(failed_h, failed_rows)]
    if rs.unreadable:
        md += ["Unreadable result files (not counted above):", ""]
        md += [f"- `{f}`: {why}" for f, why in rs.unreadable] + [""]
    if rs.summary_only:
        md += [f"Jobs listed in summary.csv without a result file: "
               + ", ".join(f"`{j}`" for j in rs.summary_only) + ".", ""]

    md += _appendix_md(rs, ctx, warn_h, warn_rows, unchecked)
    md += not_drawn_md(drawn)
    md += ["## Machine and run", ""]
    h, rows = tables.context_table(rs)
    md += [tables.render_md(h, rows)]
    return "\n".join(md)


def build_paper(rs, out):
    """Writes paper_table.md and paper_table.tex; returns the Markdown."""
    verdicts = reproduction.verdicts(rs)
    (mh, mrows, mbold), (rh, rrows, _) = tables.paper_tables(
        rs, {v.figure.key: v.verdict for v in verdicts})
    vh, vrows = reproduction.table(verdicts)
    ctx = tables.context_line(rs)
    notes = tables.paper_notes(rs)
    left = 4 if mh[0] == "Host" else 3  # text columns of the LaTeX tables
    md = (f"Per model: the EBP-Octree (bold) beside each peer. {ctx}\n\n"
          + tables.render_md(mh, [[f"**{c}**" if i in mbold and c != "–" else c for c in r]
                                  for i, r in enumerate(mrows)])
          + "\nThe published figures: did this run reproduce them? " + ctx + "\n\n"
          + tables.render_md(vh, vrows) + "\n" + reproduction.NOTE + "\n"
          + "\nRatios (above 1× the EBP-Octree is better). " + ctx + "\n\n"
          + (tables.render_md(rh, rrows) if rrows else
             "_No model has both an ebp_octree row and a peer row._\n")
          + "\n" + notes + "\n")
    write_atomic(os.path.join(out, "paper_table.md"),
                 f"# The paper's tables: `{rs.name}`\n\n" + md)
    tex = ["% Generated by plots/report.py; needs \\usepackage{booktabs}.",
           tables.render_tex(mh, mrows, "Query rates and structure sizes per model; EBP-Octree "
                             "in bold. " + notes + " " + ctx, "tab:bvhbench-paper", mbold, left)]
    tex.append(tables.render_tex(vh, vrows, "The paper's published figures and whether this "
                                 "run reproduced them. " + reproduction.NOTE + " " + ctx,
                                 "tab:bvhbench-reproduced", left_cols=len(vh)))
    if rrows:
        tex.append(tables.render_tex(rh, rrows, "EBP-Octree against each peer; above 1x the "
                                     "EBP-Octree is better. " + ctx, "tab:bvhbench-ratios", (), left))
    write_atomic(os.path.join(out, "paper_table.tex"), "\n".join(tex))
    return md


def history_section(history, out):
    """The history's section (tools/bench_history.py draws it into OUT/history/), its links
    relative to the report; None when the folder holds no history."""
    import importlib.util
    tool = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "bench_history.py")
    spec = importlib.util.spec_from_file_location("bench_history", tool)
    bench_history = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench_history)
    if bench_history.report(history, os.path.join(out, "history")) != 0:
        return None
    with open(os.path.join(out, "history", "history.md"), encoding="utf-8") as f:
        text = f.read()
    return re.sub(r"\]\((?!https?:)([^)]+)\)", r"](history/\1)", text)


def main(argv=None):
    ap = argparse.ArgumentParser(description="Charts and tables from a bvhbench result set.")
    ap.add_argument("results", help="result directory, e.g. results/default")
    ap.add_argument("--out", help="output directory (default: RESULTS/report)")
    ap.add_argument("--history", metavar="DIR",
                    help="a history of results across commits (tools/bench_history.py, e.g. "
                         "results/history): each job's rate and instructions per query per commit, "
                         "with the steps found, become the report's last section")
    ap.add_argument("--strict", action="store_true",
                    help="let a chart's exception propagate (for debugging and tests)")
    args = ap.parse_args(argv)
    try:
        rs = load(args.results)
    except ReportError as e:
        print(f"report: {e}", file=sys.stderr)
        return 2
    out = args.out or os.path.join(args.results, "report")
    os.makedirs(out, exist_ok=True)

    drawn = draw_charts(rs, out, args.strict)
    paper_md = build_paper(rs, out)
    if rs.is_stability_suite():
        stability.write(rs, out, "stability.csv", "stability.md")
    md = build_markdown(rs, drawn, paper_md)
    if args.history:
        section = history_section(args.history, out)
        if section is None:
            print(f"report: no history under {args.history}", file=sys.stderr)
            return 2
        md = md.rstrip("\n") + "\n\n" + section
    write_atomic(os.path.join(out, "report.md"), md)
    write_atomic(os.path.join(out, "report.html"),
                 html_report.render(md, out, f"bvhbench report: {rs.name}"))

    failed = [n for n, (s, _) in drawn.items() if s == "failed"]
    n_charts = sum(1 for s, _ in drawn.values() if s == "ok")
    print(f"report: {len(rs.jobs)} jobs, {n_charts} charts -> {os.path.join(out, 'report.md')}",
          file=sys.stderr)
    if failed:
        print(f"report: charts that failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
