"""What a job's inside means and how its answers were judged, as its result records them.

A method declares which definition of inside it computes (ray parity, the winding number, the
nonzero winding number, the generalized winding number with a threshold, exactly or
approximately) and the input it promises to handle (its contract); a result records that as
`job.inside`, and the harness judges the answers against it (`accuracy.judged_against`), counts
the points where the mesh's definitions disagree apart (`accuracy.definition_dependent`: never
wrong for a method that follows its own definition) and says whether the mesh is within the
method's contract (`accuracy.within_contract`). docs/results.md, "Inside: definitions".

Results made before declarations have none of these: they read as undeclared, judged against the
oracle's default definition, within no declared contract, as they were then. Standard library only.
"""

RULE_WORDS = {
    "ray_parity": "ray parity",
    "winding_number": "winding number > 1/2",
    "nonzero_winding": "nonzero winding number",
    "generalized_winding_number": "generalized winding number",
    "undeclared": "definition not declared",
    "oracle_default": "the oracle's default",
}

CONTRACT_WORDS = {
    "any": "any triangle soup",
    "closed": "closed input",
    "closed_oriented": "closed, consistently oriented input",
    "closed_oriented_manifold": "closed, oriented, manifold input",
    "embedded": "closed, outward input without self-intersections",
}


def declared(job):
    """The job's inside declaration as a dict (definition, approximate, threshold, contract);
    an undeclared one for results that record none."""
    d = job.get("job.inside")
    if not isinstance(d, dict) or not isinstance(d.get("definition"), str):
        return {"definition": "undeclared", "approximate": False, "threshold": None,
                "contract": "undeclared"}
    return d


def rule_text(name, threshold=None):
    """Words for a definition's name: "ray parity", "generalized winding number > 0.5"."""
    text = RULE_WORDS.get(name, name)
    if name == "generalized_winding_number" and isinstance(threshold, (int, float)):
        text += f" > {threshold:g}"
    return text


def definition_text(job):
    """The job's definition in words: "ray parity", "approximate generalized winding number >
    0.5", "definition not declared"."""
    d = declared(job)
    text = rule_text(d["definition"], d.get("threshold"))
    return ("approximate " if d.get("approximate") else "") + text


def legend_suffix(job):
    """The definition for a chart's legend entry ("\n  ray parity"); "" when undeclared."""
    if declared(job)["definition"] == "undeclared":
        return ""
    return "\n  " + definition_text(job)


def contract_text(job):
    """The job's contract in words ("closed input"), "" when undeclared."""
    return CONTRACT_WORDS.get(declared(job).get("contract"), "")


def outside_contract(job):
    """Whether the job ran on input its method does not promise to handle."""
    return job.get("accuracy.within_contract") is False


def contract_problem(job):
    return job.get("accuracy.contract_problem") or ""


def judged_against(job):
    """What the answers were judged against: a definition's name, or oracle_default."""
    return job.get("accuracy.judged_against") or "oracle_default"


def dependent_count(job):
    """The judged points where the mesh's definitions disagree (0 for results made before)."""
    n = job.num("accuracy.definition_dependent.count")
    return int(n) if n else 0


def dependent_examples(job):
    ex = job.get("accuracy.definition_dependent.examples")
    return ex if isinstance(ex, list) else []


def dependent_points(jobs):
    """{mesh: {(query set, index): example}} over jobs: each definition-dependent point once per
    query set (inside and distance jobs of one set share their points), with its count per set
    as `count_by_set` = {(mesh, query set): the largest count a job reported}."""
    points, counts = {}, {}
    for j in jobs:
        n = dependent_count(j)
        if not n:
            continue
        qset = j.get("job.queries.sha256") or j.get("job.queries.path") or j.kind
        key = (j.mesh, qset)
        counts[key] = max(counts.get(key, 0), n)
        for e in dependent_examples(j):
            if isinstance(e, dict) and "index" in e:
                points.setdefault(j.mesh, {}).setdefault((qset, e["index"]), dict(e, kind=j.kind))
    return points, counts


ORDER = ["ray_parity", "winding_number", "nonzero_winding", "generalized_winding_number"]


def says_text(example):
    """What the definitions say at an example point, grouped by answer: "ray parity says
    outside; winding number > 1/2, nonzero winding number, generalized winding number say
    inside"."""
    says = example.get("says") or {}
    names = sorted(says, key=lambda d: (ORDER.index(d) if d in ORDER else len(ORDER), d))
    parts = []
    for answer in (False, True):
        group = [rule_text(d) for d in names if bool(says[d]) == answer]
        if group:
            parts.append(f"{', '.join(group)} say{'s' if len(group) == 1 else ''} "
                         f"{'inside' if answer else 'outside'}")
    return "; ".join(parts)


def point_text(example):
    p = example.get("point")
    where = f"({', '.join(f'{c:.6g}' for c in p)})" if isinstance(p, list) and len(p) == 3 else \
        f"query {example.get('index')}"
    w = example.get("winding")
    return where + (f", winding number {w:.6g}" if isinstance(w, (int, float)) else "")
