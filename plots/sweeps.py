"""Parameter sweeps: which configurations of a method lie on one curve of a Pareto chart.

A suite sweeps a method by listing several values of a parameter (suites/README.md); every
value is its own job, with its own `params_key` (the non-default parameters, "" = defaults).
Nothing here names a method or a parameter: a method whose parameters vary becomes curves by
itself, whatever its parameters are called.

How configurations are grouped (`series()`):
- A parameter whose value is a number (leaf_factor=3, voxel=0.5, max_planes=4) is a *knob*:
  configurations that differ only in the value of the same knob(s) lie on one curve, ordered
  by the knob's value.
- Any other non-default value (coherent=true, band=fixed, a store path, a sign type) names a
  *variant*: each variant gets curves of its own, as a path-coherent method is its own row.
- The configuration with no knob turned (the defaults, or the variant alone) is the anchor: it
  is the knobs' default value, so it joins every curve of its variant, at that value.
"""
from collections import namedtuple

from results_io import as_float   # the float a value spells; None for words, booleans, NaN

Series = namedtuple("Series", "variant knobs points")
# variant: tuple of (name, value) of the non-numeric parameters, () for none.
# knobs: tuple of the numeric parameter names turned along the curve, () for a lone point.
# points: [(knob values tuple, payload)] ordered by the knob values.


def parse_key(params_key):
    """'a=1,b=x' -> {'a': '1', 'b': 'x'} (the harness's params_key: sorted, comma-separated)."""
    out = {}
    for part in (params_key or "").split(","):
        if "=" in part:
            k, v = part.split("=", 1)
            out[k] = v
    return out


def split_key(params_key):
    """(variant, knobs) of a params_key: its non-numeric and its numeric parameters, each as a
    tuple of (name, value) sorted by name (knob values as floats)."""
    variant, knobs = [], []
    for k, v in sorted(parse_key(params_key).items()):
        n = as_float(v)
        if n is None:
            variant.append((k, v))
        else:
            knobs.append((k, n))
    return tuple(variant), tuple(knobs)


def series(configs, resolved_value):
    """Curves of one method's configurations.

    configs: [(params_key, payload)] of one method, one entry per configuration.
    resolved_value(payload, name): the value the configuration ran with for a parameter it left
      at its default (from the result's resolved `job.params`), or None when unknown.
    Returns [Series], each knob curve holding its variant's anchor (when the suite ran it) at the
    knob's resolved default value. An anchor whose variant turned no knob is a lone point.
    """
    groups = {}       # (variant, knob names) -> [(knob values, payload)]
    anchors = {}      # variant -> [payload] of configurations with no knob turned
    for key, payload in configs:
        variant, knobs = split_key(key)
        if knobs:
            names = tuple(k for k, _ in knobs)
            groups.setdefault((variant, names), []).append((tuple(v for _, v in knobs), payload))
        else:
            anchors.setdefault(variant, []).append(payload)
    out = []
    for (variant, names), pts in groups.items():
        for payload in anchors.get(variant, []):
            values = tuple(as_float(resolved_value(payload, n)) for n in names)
            if all(v is not None for v in values):
                pts.append((values, payload))
        out.append(Series(variant, names, sorted(pts, key=lambda p: p[0])))
    knobbed = {variant for variant, _ in groups}
    for variant, payloads in anchors.items():
        if variant not in knobbed:
            out += [Series(variant, (), [((), p)]) for p in payloads]
    return sorted(out, key=lambda s: (s.variant, s.knobs))


def series_label(method, s):
    """'ebp_octree · leaf_factor', 'embree (coherent=true)', 'openvdb (band=fixed) · ex_band'."""
    text = method
    if s.variant:
        text += " (" + ",".join(f"{k}={v}" for k, v in s.variant) + ")"
    if s.knobs:
        text += " \u00b7 " + ",".join(s.knobs)
    return text


def knob_text(values):
    """Point label of a knob setting: '3', '0.5', or '2/8' for a grid of two knobs."""
    return "/".join(f"{v:g}" for v in values)
