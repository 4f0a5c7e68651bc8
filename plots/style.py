"""Visual conventions shared by every chart: one colour and marker per method, status colours.

A method keeps its colour in every chart of every report. Known methods have fixed entries;
an unknown one (a newly added method folder) gets a stable colour derived from its name, so
adding a method needs no change here (add an entry only to choose a nicer colour).
"""
import zlib

import matplotlib

matplotlib.use("Agg")  # headless: reports are built on CI machines and over ssh
matplotlib.rcParams["svg.fonttype"] = "none"   # SVG text stays text: smaller, searchable
matplotlib.rcParams["svg.hashsalt"] = "bvhbench"  # stable ids: re-running gives the same SVG

METHOD_COLORS = {
    "ebp_octree": "#d62728",   # the star method: red, drawn on top
    "cgal_aabb": "#1f77b4",
    "embree": "#2ca02c",
    "openvdb": "#9467bd",
    "brute_force": "#7f7f7f",
}
METHOD_MARKERS = {
    "ebp_octree": "o",
    "cgal_aabb": "s",
    "embree": "^",
    "openvdb": "D",
    "brute_force": "v",
}

_FALLBACK_COLORS = ["#ff7f0e", "#8c564b", "#e377c2", "#bcbd22", "#17becf",
                    "#aec7e8", "#ffbb78", "#98df8a", "#c5b0d5", "#c49c94"]
_FALLBACK_MARKERS = ["v", "P", "*", "h", "<", ">", "p", "X"]


def _stable_index(name, n):
    return zlib.crc32(name.encode("utf-8")) % n


def method_color(method):
    """Fixed colour of a method; unknown methods get a stable colour from their name."""
    if method in METHOD_COLORS:
        return METHOD_COLORS[method]
    return _FALLBACK_COLORS[_stable_index(method, len(_FALLBACK_COLORS))]


def method_marker(method):
    if method in METHOD_MARKERS:
        return METHOD_MARKERS[method]
    return _FALLBACK_MARKERS[_stable_index(method, len(_FALLBACK_MARKERS))]


# Status colours of the stability matrix (statuses and their order: stability.SEVERITY).
# "ok_wrong" is an ok job whose answers were wrong.
STATUS_COLORS = {
    "ok": "#4daf4a",
    "ok_wrong": "#ffd92f",
    "definition_dependent": "#a6d96a",  # right by its own definition where definitions disagree
    "outside_contract": "#c6dbef",      # input it does not promise to handle
    "unchecked": "#b8e0b0",       # ok but no oracle: nothing known about its answers
    "unsupported": "#d9d9d9",
    "rejected_input": "#80b1d3",
    "error": "#fdb462",
    "timeout": "#bc80bd",
    "oom": "#a65628",
    "crash": "#e41a1c",
    "missing": "#ffffff",
    "not_run": "#f0f0f0",        # its group's child died in an earlier job (suite --resume runs it)
}
STATUS_LABELS = {
    "ok": "ok",
    "ok_wrong": "ok, wrong answers",
    "definition_dependent": "ok, definition-dependent",
    "outside_contract": "outside its contract",
    "unchecked": "ok, no oracle",
    "unsupported": "unsupported",
    "rejected_input": "rejected input",
    "error": "error",
    "timeout": "timeout",
    "oom": "out of memory",
    "crash": "crash",
    "missing": "not run",
    "not_run": "not run (its structure's child died earlier)",
}

HAPTIC_RATE_HZ = 1000.0          # a haptic loop needs 1 kHz
HAPTIC_DEADLINE_NS = 1_000_000   # i.e. 1 ms per query

FIGSIZE_PANEL = (5.2, 4.0)       # one panel, inches
DPI = 130
