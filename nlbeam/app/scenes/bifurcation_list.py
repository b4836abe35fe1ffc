"""The bifurcations of a diagram as a person reads them: sorted by frequency, each with its
branch, order and error, near duplicates merged.

Two reports of one point are merged:

- on one branch, bifurcations whose frequencies lie within the larger of their errors (a
  grazing point where a multiplier jumps is reported as grazing and again as a fold or a
  period doubling 'at grazing'): one row, the kinds joined by '+', the frequency of the
  best-located report, the error the largest of the merged ones or their spread;
- the fold of order 2n at the start of a branch switched at a period doubling of order n (the
  doubled orbit has the multiplier +1 there): listed once, as the period doubling, with the
  note 'order-2n branch k starts here'.

Errors are ``numbers.bifurcation_error`` (Hz): the bracket, the integration
error estimate or refinement error, and the location accuracy the diagram asked for.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .numbers import bifurcation_error, error_bound, with_error, xmax_error

__all__ = ["ListedBifurcation", "list_bifurcations", "bifurcation_rows"]

# the order kinds are named in when several reports merge
_KIND_ORDER = ("fold", "period-doubling", "neimark-sacker", "grazing")


@dataclass
class ListedBifurcation:
    """One row: kind ('fold', 'period-doubling+grazing', ...), order, branch index, frequency
    (Hz) and its error (Hz), xmax (m) and its error (m), note, and the merged Bifurcations."""

    kind: str
    order: int
    branch: int
    frequency: float
    frequency_error: float
    xmax: float
    xmax_error: float
    note: str
    merged: list


def _kind_key(kind):
    return _KIND_ORDER.index(kind) if kind in _KIND_ORDER else len(_KIND_ORDER)


def _merge(group, frc):
    errs = [bifurcation_error(b, frc) for b in group]
    best = min(range(len(group)), key=lambda i: errs[i] if math.isfinite(errs[i]) else math.inf)
    b = group[best]
    fs = [g.frequency for g in group]
    err = max([e for e in errs if math.isfinite(e)] + [max(fs) - min(fs)], default=math.nan)
    kinds = sorted({g.kind for g in group}, key=_kind_key)
    notes = [g.note for g in group if g.note]
    return ListedBifurcation("+".join(kinds), int(b.order), int(b.branch), float(b.frequency),
                             float(err), float(b.xmax), float(xmax_error(b, frc, err)),
                             "; ".join(dict.fromkeys(notes)), list(group))


def list_bifurcations(frc):
    """The bifurcations of ``frc`` (a continuation.FrequencyResponse) merged as the module
    doc says, sorted by frequency (then order, branch): a list of ListedBifurcation."""
    by_branch = {}
    for b in frc.bifurcations:
        by_branch.setdefault(int(b.branch), []).append(b)
    rows = []
    for branch in by_branch.values():
        branch.sort(key=lambda b: b.frequency)
        group, hi, e_hi = [], -math.inf, 0.0
        for b in branch:
            e = bifurcation_error(b, frc)
            e = e if math.isfinite(e) else 0.0
            if group and b.frequency - hi <= max(e, e_hi):
                group.append(b)
                e_hi = max(e_hi, e)
            else:
                if group:
                    rows.append(_merge(group, frc))
                group, e_hi = [b], e
            hi = b.frequency
        if group:
            rows.append(_merge(group, frc))
    rows = _fold_at_doubling(rows)
    rows.sort(key=lambda r: (r.frequency, r.order, r.branch))
    return rows


def _fold_at_doubling(rows):
    """Drop the fold of order 2n that repeats a period doubling of order n (see module doc)."""
    pds = [r for r in rows if "period-doubling" in r.kind.split("+")]
    keep = []
    for r in rows:
        twin = None
        if r.kind == "fold":
            for p in pds:
                if (r.order == 2 * p.order and abs(r.frequency - p.frequency)
                        <= max(r.frequency_error, p.frequency_error)):
                    twin = p
                    break
        if twin is None:
            keep.append(r)
            continue
        twin.merged.extend(r.merged)
        extra = f"order-{r.order} branch {r.branch} starts here"
        twin.note = f"{twin.note}; {extra}" if twin.note else extra
    return keep


def bifurcation_rows(frc, variant=""):
    """Table rows (dicts) of ``list_bifurcations(frc)``: variant, branch, order, kind,
    frequency_error_hz (the error, one digit rounded up), frequency_hz to that digit (not
    one further when rounding up reaches the next decade: 9.5e-7 prints as 1e-06 and the
    frequency to 1e-6), xmax_m (to the digits its error supports), note."""
    rows = []
    for r in list_bifurcations(frc):
        e = error_bound(r.frequency_error)
        rows.append({"variant": variant, "branch": r.branch, "order": r.order, "kind": r.kind,
                     "frequency_hz": with_error(r.frequency, float(e)),
                     "frequency_error_hz": e,
                     "xmax_m": with_error(r.xmax, r.xmax_error), "note": r.note})
    return rows
