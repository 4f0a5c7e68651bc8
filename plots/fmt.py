"""Number formatting for tables and axis ticks."""
import math


def si(x, unit="", digits=3):
    """1234567 -> '1.23 M' + unit. None -> '–'."""
    if x is None:
        return "–"
    if x == 0:
        return f"0 {unit}".strip()
    prefixes = [(1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k"), (1, ""), (1e-3, "m"),
                (1e-6, "µ"), (1e-9, "n")]
    for i, (scale, p) in enumerate(prefixes):
        if abs(x) >= scale:
            # 999992 is '1.00 M', not '1e+03 k': rounding may carry into the next prefix.
            if i > 0 and abs(float(f"{x / scale:.{digits}g}")) >= 1000:
                scale, p = prefixes[i - 1]
            return f"{x / scale:.{digits}g} {p}{unit}".strip()
    return f"{x:.{digits}g} {unit}".strip()


def hz(x):
    return si(x, "Hz")


def count(x):
    """Triangle counts: '69.5k', '28.1M'."""
    if x is None:
        return "–"
    return si(x, "", 3).replace(" ", "")


def nbytes(x):
    """Decimal units, as on disk: '12.3 MB'."""
    if x is None:
        return "–"
    return si(x, "B", 3)


def seconds(x):
    if x is None:
        return "–"
    if x >= 1:
        return f"{x:.3g} s"
    return si(x, "s")


def duration_ns(ns):
    """Latency tick labels: '800 ns', '12 µs', '1 ms'."""
    if ns is None:
        return "–"
    return si(ns * 1e-9, "s", 3)


def sci(x, digits=2):
    """Error rates: '0', '3.2e-04'."""
    if x is None:
        return "–"
    if x == 0:
        return "0"
    if 1e-2 <= abs(x) < 1e3:
        return f"{x:.{digits + 1}g}"
    return f"{x:.{digits - 1}e}"


def ratio(x):
    if x is None or not math.isfinite(x):
        return "–"
    return f"{x:.3g}×"
