"""Numbers of the result tables to the digits their errors support, so that a table
regenerated on another machine (other round-off) prints the same: each value to the decade of
its error's first digit (``with_error``), the error as one digit rounded up (``error_bound``);
the errors of a diagram's bifurcation frequencies and xmax (``bifurcation_error``,
``xmax_error``).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["with_error", "error_bound", "error_digit", "moment_cells", "bifurcation_error",
           "xmax_error", "GRAZING_REL", "LOCATED_REL", "XMAX_REL"]


def with_error(value, error):
    """``value`` printed to the decade of the first significant digit of its ``error`` (so
    that a value that round-off moves well within its error prints the same); '%.10g' when
    the error is not a positive finite number."""
    v, e = float(value), float(error)
    if not (math.isfinite(v) and math.isfinite(e) and e > 0):
        return f"{v:.10g}"
    k = math.floor(math.log10(e))  # resolution 10^k
    q = round(v / 10.0 ** k)
    if q == 0:
        return "0"
    if -12 <= k <= 0 and 1e-4 <= abs(v) < 1e7:
        return f"{q * 10.0 ** k:.{-k}f}"
    if 0 < k and abs(v) < 1e15:
        return str(int(q) * 10 ** k)
    sig = int(math.floor(math.log10(abs(q)))) + 1  # significant digits
    return f"{q * 10.0 ** k:.{max(sig - 1, 0)}e}"


def error_bound(error):
    """An error printed as one significant digit, rounded up ('%.0e' of ceil)."""
    e = float(error)
    if not (math.isfinite(e) and e > 0):
        return f"{e:.10g}"
    k = math.floor(math.log10(e))
    return f"{math.ceil(e / 10.0 ** k - 1e-9) * 10.0 ** k:.0e}"


def error_digit(error):
    """A one-standard-deviation error printed as one significant digit, rounded to nearest
    ('%.1g'): a statistical error is itself uncertain (by about 1/sqrt(2 dof)), so its
    second digit says nothing."""
    e = float(error)
    if not (math.isfinite(e) and e > 0):
        return f"{e:.10g}"
    return f"{e:.1g}"


def moment_cells(value, se):
    """(value, se) cells of a statistic with a standard error: the error to one significant
    digit (``error_digit``) and the value to that digit's decade, so the value's last digit
    is the uncertain one (another record of the same length, or the same record under
    other round-off, which an impacting response amplifies into another realization,
    moves it by about +-se); (value '%.10g', None) when se is not a positive finite
    number."""
    if se is None or not (math.isfinite(float(se)) and float(se) > 0):
        return f"{float(value):.10g}", None
    e = error_digit(se)
    return with_error(value, float(e)), e


# a grazing point's bracket is what 8 bisections of a tracer step leave (1e-7..1e-5 of f on
# the paper diagram) and moves with round-off: grazing frequencies (and bifurcations reported
# at a grazing point) are printed to 1e-5 of f
GRAZING_REL = 1e-5
# a located fold / period doubling moves by ~1e-9 of f with round-off (the corrector's
# tolerance), whatever its bracket: printed to 1e-7 of f at most
LOCATED_REL = 1e-7
# xmax: to 1e-6 of itself at most (and less where the branch is steep)
XMAX_REL = 1e-6


def bifurcation_error(b, frc):
    """The error (Hz) a diagram's bifurcation frequency is printed with: its bracket
    (``tolerance``), its estimated integration error where known (``error`` /
    ``integrator_error``), and at least the location accuracy the diagram asked for
    (settings 'bif_tol', relative) and LOCATED_REL, or for a grazing point (or a bifurcation
    reported at one) GRAZING_REL."""
    e = [float(b.tolerance), LOCATED_REL * abs(float(b.frequency))]
    if b.kind == "grazing" or not getattr(b, "smooth", True):
        e.append(GRAZING_REL * abs(float(b.frequency)))
    for name in ("error", "integrator_error"):
        v = getattr(b, name, None)
        if v is not None and math.isfinite(float(v)):
            e.append(float(v))
    rel = frc.settings.get("bif_tol") if getattr(frc, "settings", None) else None
    if rel is not None and math.isfinite(float(rel)):
        e.append(float(rel) * abs(float(b.frequency)))
    e = [x for x in e if math.isfinite(x)]
    return max(e) if e else math.nan


def xmax_error(b, frc, e_f):
    """Error (m) of a bifurcation's xmax: the branch's slope |dxmax/df| next to it times the
    frequency error (not at a fold: the branch is vertical there, and the located point's
    xmax is as good as its arclength bracket, far below XMAX_REL), or the branch point's xmax
    error where known, and at least XMAX_REL of it."""
    e = XMAX_REL * abs(float(b.xmax))
    if b.kind == "fold" and getattr(b, "smooth", True):
        e_f = math.nan
    try:
        br = frc.branches[int(b.branch)]
    except (IndexError, ValueError, TypeError):
        return e
    F, X = np.asarray(br.frequency, dtype=float), np.asarray(br.xmax, dtype=float)
    if len(F) >= 2 and math.isfinite(e_f):
        j = int(np.argmin(np.abs(F - b.frequency)))
        lo, hi = max(j - 1, 0), min(j + 1, len(F) - 1)
        dF = abs(F[hi] - F[lo])
        slope = abs(X[hi] - X[lo]) / dF if dF > 0 else np.inf
        e = max(e, slope * e_f if math.isfinite(slope) else abs(float(b.xmax)))
    xe = getattr(br, "xmax_error", None)
    if xe is not None:
        j = int(np.argmin(np.abs(F - b.frequency)))
        if math.isfinite(float(xe[j])):
            e = max(e, float(xe[j]))
    return e
