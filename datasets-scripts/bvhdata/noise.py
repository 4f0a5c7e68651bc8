"""Multi-scale noise on unit directions: random plane waves, octave by octave. The scan-like
family's radial displacement, in memory (families.py) and streamed (streamed_scan.py), which must
draw and evaluate the same waves to write the same surface."""
from __future__ import annotations

import math

import numpy as np


def noise_params(rng: np.random.Generator, octaves: int, base_frequency: float, amplitude: float,
                 waves: int) -> list:
    """The random plane waves of multi-scale noise, octave by octave (amplitude halves, frequency
    doubles per octave): [(wave vectors, phases, amplitude)]."""
    params = []
    for o in range(octaves):
        w = rng.standard_normal((waves, 3))
        w /= np.linalg.norm(w, axis=1, keepdims=True)
        phase = rng.uniform(0, 2 * math.pi, waves)
        params.append((w * (2 * math.pi * base_frequency * 2**o), phase,
                       amplitude * 0.5**o * math.sqrt(2.0 / waves)))
    return params


def noise_eval(d: np.ndarray, params: list) -> np.ndarray:
    """The noise of `params` (noise_params) at unit directions d, in chunks."""
    out = np.zeros(len(d))
    chunk = 1 << 20
    for s in range(0, len(d), chunk):
        dd = d[s:s + chunk]
        acc = np.zeros(len(dd))
        for w, phase, a in params:
            acc += a * np.sin(dd @ w.T + phase).sum(1)
        out[s:s + chunk] = acc
    return out
