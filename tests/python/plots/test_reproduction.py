"""The paper table's verdicts: did this run reproduce each published figure (plots/reproduction.py),
judged on hand-made results."""
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "plots"))

import reproduction  # noqa: E402
import results_io  # noqa: E402
import tables  # noqa: E402

PAPER_SCALE = int(tables.PAPER_REFERENCE["min_polygons"])


def job(qps, query="distance", kind="haptic", method="ebp_octree", params_key="",
        mesh="bunny_32m", triangles=PAPER_SCALE + 1, status="ok", dist_err=0.0,
        wrong_far=0):
    return results_io.Job({
        "status": status,
        "job": {"id": f"{mesh}__{kind}__{query}__{method}_{params_key}", "method": method,
                "params_key": params_key, "query": query,
                "mesh": {"name": mesh, "triangles": triangles},
                "queries": {"kind": kind, "n": 1000}},
        "queries": {"throughput_qps": {"median": qps}},
        "accuracy": {"inside": {"wrong_far": wrong_far}} if query == "inside" else
                    {"distance": {"rel_error": {"max": dist_err, "p99": dist_err},
                                  "sign_wrong": 0, "non_finite": 0}},
    }, "x.json")


def verdicts(*jobs):
    rs = results_io.ResultSet("/tmp/default", list(jobs), [], [])
    return {v.figure.key: v for v in reproduction.verdicts(rs)}


def test_met_when_the_best_exact_configuration_reaches_the_figure():
    v = verdicts(job(4e5), job(1.2e6, params_key="coherent=true"))["dist_haptic"]
    assert v.verdict == reproduction.MET and v.rate == 1.2e6
    assert "ebp_octree:coherent=true" in v.evidence and "bunny_32m" in v.evidence


def test_not_met_when_it_falls_short_on_one_model_of_the_papers_scale():
    v = verdicts(job(2e6), job(9e5, mesh="lucy_28m"))["dist_haptic"]
    assert v.verdict == reproduction.NOT_MET and v.rate == 9e5
    assert "lucy_28m" in v.evidence and "slowest of 2" in v.evidence


def test_not_measured_without_a_model_of_the_papers_scale():
    v = verdicts(job(3e6, mesh="bunny_1m", triangles=1_000_000))
    assert v["dist_haptic"].verdict == reproduction.NOT_MEASURED
    assert v["dist_haptic"].rate is None
    # The rate on the largest smaller model is given for reference, not taken as the verdict.
    assert "bunny_1m" in v["dist_haptic"].evidence and "3 MHz" in v["dist_haptic"].evidence
    # A path the run did not measure at all.
    assert v["pis_random"].verdict == reproduction.NOT_MEASURED


def test_wrong_answers_do_not_reproduce_an_exact_figure():
    fast_but_wrong = job(5e6, dist_err=1e-2)
    v = verdicts(fast_but_wrong)["dist_haptic"]
    assert v.verdict == reproduction.NOT_MET and "wrong answers" in v.evidence
    # An exact configuration beside it is the one judged.
    v = verdicts(fast_but_wrong, job(2e5, params_key="leaf_factor=3"))["dist_haptic"]
    assert v.verdict == reproduction.NOT_MET and v.rate == 2e5


def test_only_the_ebp_octree_and_only_ok_jobs_count():
    v = verdicts(job(5e6, method="embree"), job(5e6, status="timeout"))["dist_haptic"]
    assert v.verdict == reproduction.NOT_MEASURED


def test_each_figure_is_judged_on_its_own_query_and_path():
    v = verdicts(job(3e3, query="inside", kind="random"), job(3e4, query="inside", kind="haptic",
                                                             wrong_far=0),
                 job(1e6))
    assert v["pis_random"].verdict == reproduction.MET          # 3 kHz >= 2.5 kHz
    assert v["pis_haptic"].verdict == reproduction.NOT_MET      # 30 kHz < 32 kHz
    assert v["dist_haptic"].verdict == reproduction.MET         # 1 MHz, the figure itself


def test_the_paper_table_has_a_reproduced_row_and_a_table_of_verdicts():
    jobs = [job(3e3, query="inside", kind="random"), job(5e5)]
    rs = results_io.ResultSet("/tmp/default", jobs, [], [])
    vs = reproduction.verdicts(rs)
    (header, rows, _), _ = tables.paper_tables(rs, {v.figure.key: v.verdict for v in vs})
    row = rows[-1]
    assert row[0] == "Reproduced by this run?"
    assert row[header.index("PiS random")] == "met"
    assert row[header.index("PiS haptic")] == "not measured"
    assert row[header.index("Distance haptic")] == "not met"
    h, detail = reproduction.table(vs)
    assert h[-1] == "Reproduced" and [r[-1] for r in detail] == ["met", "not measured",
                                                                 "not met", "not measured"]


def test_the_contact_path_is_a_column_of_its_own():
    # A probe in contact (the contact query kind) is judged apart from the haptic path with its
    # approach and leave phases: fast in contact does not make the haptic figure, nor the reverse.
    rs = results_io.ResultSet("/tmp/default", [job(5e5), job(1.1e6, kind="contact")], [], [])
    v = {x.figure.key: x for x in reproduction.verdicts(rs)}
    assert v["dist_contact"].verdict == reproduction.MET and v["dist_contact"].rate == 1.1e6
    assert v["dist_haptic"].verdict == reproduction.NOT_MET and v["dist_haptic"].rate == 5e5
    (header, rows, _), (rh, ratios, _) = tables.paper_tables(rs)
    star = next(r for r in rows if r[header.index("Method")] == "ebp_octree")
    assert star[header.index("Distance contact")] == "1.1 MHz"
    assert star[header.index("Distance haptic")] == "500 kHz"
    assert "Distance contact: EBP/peer" in rh
