"""Progress messages on stderr, with the time since the run started."""
from __future__ import annotations

import sys
import time

_T0 = time.monotonic()
quiet = False


def log(msg: str) -> None:
    if not quiet:
        print(f"[{time.monotonic() - _T0:7.1f}s] {msg}", file=sys.stderr, flush=True)


class Bar:
    """A percentage line for long loops, printed at most every ~10 %."""

    def __init__(self, label: str):
        self.label = label
        self.last = -1

    def __call__(self, done: int, total: int) -> None:
        if total <= 0:
            return
        pct = int(100 * done / total) // 10 * 10
        if pct > self.last and total > 2_000_000:
            self.last = pct
            log(f"{self.label}: {pct}%")
