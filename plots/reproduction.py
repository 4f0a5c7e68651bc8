"""Did this run reproduce the paper's published figures? One verdict per figure.

The paper (tables.PAPER_REFERENCE) publishes three query rates of the EBP-Octree, single
thread, on models of 25M+ polygons: point-in-solid at 2.5 kHz on random points and 32 kHz on
haptic-like paths, and distance with contact normal at about 1 MHz on haptic paths. Each is
judged from this run's own results, and nothing else:

- the candidates are the EBP-Octree's ok jobs of that query on that kind of path, any
  configuration (a path-coherent or out-of-core variant is the EBP-Octree too: the paper's
  figures are of its out-of-core, path-following use), whose answers are right: a job with an
  accuracy problem (tables.accuracy_problems) does not reproduce an exact method's figure;
- only models of the paper's scale count (at least PAPER_REFERENCE["min_polygons"] triangles):
  a rate on a smaller model says nothing about 25M polygons;
- on each such model the best candidate configuration stands for the EBP-Octree; the figure is
  **met** when that rate reaches the published one on every such model, **not met** when it
  falls short on one (the slowest model is named), **not measured** when the run has no such
  model or no candidate on it. The figures on smaller models are shown beside, for reference.

The published figures were measured on 2015 hardware; the verdict compares rates as they are,
on the machine of this run (named by the report's context line).
"""
from collections import namedtuple

import fmt
import tables

Figure = namedtuple("Figure", "key label query kind hz")

LABELS = {"pis_random": "Point-in-solid, random points",
          "pis_haptic": "Point-in-solid, haptic path",
          "dist_haptic": "Distance and normal, haptic path",
          "dist_contact": "Distance and normal, probe in contact (contact path)"}
# The paper table's rate columns, each with its published rate.
FIGURES = [Figure(key, LABELS[key], query, kind, tables.PAPER_REFERENCE[key + "_hz"])
           for key, query, kind in tables.RATE_COLUMNS]

MET, NOT_MET, NOT_MEASURED = "met", "not met", "not measured"

Verdict = namedtuple("Verdict", "figure verdict rate job evidence")
# rate: the run's figure (queries/s) the verdict rests on, None when not measured; job: its
# result (Job) or None; evidence: one sentence saying what was compared.


def _best_per_model(jobs):
    """{mesh: the job with the highest throughput on it}."""
    best = {}
    for j in jobs:
        if j.mesh not in best or j.qps > best[j.mesh].qps:
            best[j.mesh] = j
    return best


def _where(job):
    return f"`{job.config}` on {job.mesh} ({fmt.count(job.triangles)} triangles)"


def judge(rs, figure):
    """The Verdict of one published figure from the result set's jobs on regular models."""
    min_tri = tables.PAPER_REFERENCE["min_polygons"]
    on_path = [j for j in rs.model_jobs() if j.method == tables.STAR and j.ok
               and j.query == figure.query and j.kind == figure.kind and j.qps]
    right = [j for j in on_path if not tables.accuracy_problems(j)]
    wrong = len(on_path) - len(right)
    at_scale = _best_per_model(j for j in right if (j.triangles or 0) >= min_tri)
    smaller = _best_per_model(j for j in right if (j.triangles or 0) < min_tri)
    wrong_at_scale = [j for j in on_path if j not in right and (j.triangles or 0) >= min_tri]
    if at_scale:
        slowest = min(at_scale.values(), key=lambda j: j.qps)
        met = slowest.qps >= figure.hz
        many = len(at_scale) > 1
        evidence = (f"{fmt.hz(slowest.qps)}, {_where(slowest)}"
                    + (f", the slowest of {len(at_scale)} models of the paper's scale"
                       if many else ""))
        return Verdict(figure, MET if met else NOT_MET, slowest.qps, slowest, evidence)
    if wrong_at_scale:
        evidence = (f"{len(wrong_at_scale)} ok job(s) on models of the paper's scale, all with "
                    f"wrong answers (see the report's accuracy lines), e.g. {_where(wrong_at_scale[0])}")
        return Verdict(figure, NOT_MET, None, wrong_at_scale[0], evidence)
    if smaller:
        largest = max(smaller.values(), key=lambda j: (j.triangles or 0, j.qps))
        evidence = (f"no model of {fmt.count(min_tri)}+ triangles in this run; on the largest, "
                    f"{fmt.hz(largest.qps)}, {_where(largest)}")
        return Verdict(figure, NOT_MEASURED, None, None, evidence)
    evidence = "no ok EBP-Octree job with right answers on this kind of path"
    if wrong:
        evidence += f" ({wrong} ok job(s) gave wrong answers)"
    return Verdict(figure, NOT_MEASURED, None, None, evidence)


def verdicts(rs):
    return [judge(rs, f) for f in FIGURES]


def table(verdicts_):
    """(header, rows) of the published figures and whether this run reproduced each, from
    verdicts(rs)."""
    header = ["Published figure", "Paper (2016)", "This run (EBP-Octree)", "Reproduced"]
    rows = []
    for v in verdicts_:
        published = ("≈" if v.figure.query == "distance" else "") + fmt.hz(v.figure.hz)
        rows.append([v.figure.label, published, v.evidence, v.verdict])
    return header, rows


NOTE = ("Reproduced: met when the EBP-Octree's best configuration with right answers "
        "reaches the published rate on every model of the paper's scale (25M+ triangles) in "
        "this run, not met when it falls short on one (or answers wrongly there), not measured when the run has "
        "no such model (the rate on its largest model is given for reference). Any "
        "configuration counts (path-coherent, out of core), as the paper's are of its "
        "out-of-core use on paths; published figures are from 2015 hardware.")
