"""Contact identification from measured collisions (the paper's section 2.3).

Input: the indentation delta (m, > 0 in contact), its rate delta' (m/s) and the contact
force F (N) of one or many collisions, sampled at any rate (uniform or not). Either three
1-D arrays holding one record (collisions are the runs of samples with delta > 0, the
samples between them out of contact), or three equally long lists with one array per
collision.

Two estimators:

- ``method="paper"`` (eqs. 2, 5, 6): ``K_hertz`` from F and delta at maximum indentation
  (delta' = 0, interpolated between samples), then per collision the hysteresis-loop energy
  ``Delta T = closed integral F d delta`` gives ``mu = Delta T / closed integral delta^1.5
  delta' d delta`` and ``e = sqrt(1 - 4 mu delta'_minus / (3 K))``. Errors: the scatter
  between collisions (standard error of the mean; None with one collision).
- ``method="least-squares"``: the chosen law fitted to every sample in contact. All three
  laws are linear in their coefficients once delta'_minus of each collision is known
  (the rate at the onset), so the fit is an ordinary linear least-squares problem; the
  standard errors come from the heteroscedasticity-consistent (sandwich) covariance and,
  for e, the delta method.

Both are biased by sampling (quadratures and interpolation between samples) and by noise in
delta and delta' (errors in the regressors); noise in F alone is what the least-squares
standard errors describe. ``ContactFit.model(m=..., k=..., b=...)`` builds a ``BeamImpact``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import choice, positive
from .summary import Summary

LAWS = ("hertz", "lankarani-nikravesh", "hunt-crossley")
METHODS = ("least-squares", "paper")
MIN_SAMPLES = 5  # samples in contact a collision needs to be used


@dataclass(frozen=True, repr=False)
class Collision(Summary):
    """One contact: delta (m), delta' (m/s), F (N) at its samples in contact, and the
    penetration rate at the onset delta'_minus (m/s, > 0)."""

    delta: np.ndarray
    rate: np.ndarray
    force: np.ndarray
    rate_onset: float


@dataclass(frozen=True, repr=False)
class ContactFit(Summary):
    """Estimated contact parameters with standard errors.

    K_hertz (N/m^1.5); e (restitution, Lankarani-Nikravesh; for Hunt-Crossley the
    restitution equivalent to mu at the mean onset rate, eq. 6); mu (N s/m^2.5, Hunt-Crossley;
    for the paper's recipe the mean of the per-collision values); se_*: standard errors (None
    where the data cannot give one); residual_rms: rms of F - fitted F over all samples in
    contact (N); n_collisions, n_samples: the data used; rates_onset (m/s) per collision.
    """

    law: str
    method: str
    K_hertz: float
    e: float | None
    mu: float | None
    se_K_hertz: float | None
    se_e: float | None
    se_mu: float | None
    residual_rms: float
    n_collisions: int
    n_samples: int
    rates_onset: np.ndarray

    def force(self, delta, rate, rate_onset):
        """Contact force (N) of the fitted law at indentation delta (m), rate (m/s) and the
        collision's onset rate (m/s); zero out of contact."""
        d = np.clip(np.asarray(delta, dtype=float), 0.0, None)
        r = np.asarray(rate, dtype=float)
        d15 = d ** 1.5
        if self.law == "hertz":
            return self.K_hertz * d15
        if self.law == "hunt-crossley":
            return (self.K_hertz + self.mu * r) * d15
        c = 0.75 * (1.0 - self.e ** 2)
        return self.K_hertz * d15 * (1.0 + c * r / rate_onset)

    def model(self, **parameters):
        """A ``BeamImpact`` with the fitted contact (``m``, ``k``, ``b``, ``clamp`` as keyword
        arguments; other defaults are the paper's)."""
        from .systems import BeamImpact

        kw = dict(K_hertz=self.K_hertz, contact=self.law)
        if self.law == "lankarani-nikravesh":
            kw["e"] = self.e
        elif self.law == "hunt-crossley":
            kw["mu"] = self.mu
        kw.update(parameters)
        return BeamImpact(**kw)

    def __str__(self):
        def pm(v, se, unit=""):
            s = f"{v:.6g}" if se is None else f"{v:.6g} +- {se:.2g}"
            return s + (f" {unit}" if unit else "")
        lines = [f"{self.law} law, {self.method} ({self.n_collisions} collisions, "
                 f"{self.n_samples} samples in contact)",
                 f"  K_hertz = {pm(self.K_hertz, self.se_K_hertz, 'N/m^1.5')}"]
        if self.e is not None:
            lines.append(f"  e = {pm(self.e, self.se_e)}")
        if self.mu is not None:
            lines.append(f"  mu = {pm(self.mu, self.se_mu, 'N s/m^2.5')}")
        lines.append(f"  residual rms = {self.residual_rms:.3g} N")
        return "\n".join(lines)


def _as_array(name, value):
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be an array of real numbers") from None
    if a.ndim != 1:
        raise ValueError(f"{name}: must be 1-D, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        i = int(np.flatnonzero(~np.isfinite(a))[0])
        raise ValueError(f"{name}: sample {i} is not finite ({a[i]!r})")
    return a


def _onset_rate(d, r, i0):
    """Penetration rate at the onset of the run starting at sample i0: interpolated to
    delta = 0 from the sample before when there is one, else the first sample's rate."""
    if i0 > 0 and d[i0 - 1] <= 0 < d[i0]:
        w = -d[i0 - 1] / (d[i0] - d[i0 - 1])
        return float(r[i0 - 1] + w * (r[i0] - r[i0 - 1]))
    return float(r[i0])


def collisions(delta, rate, force, *, min_samples=MIN_SAMPLES):
    """Split measured data into ``Collision`` objects (see the module docstring for the two
    input forms). Runs shorter than ``min_samples`` samples in contact are left out."""
    if isinstance(delta, (list, tuple)) and len(delta) and np.ndim(delta[0]) == 1:
        if not (isinstance(rate, (list, tuple)) and isinstance(force, (list, tuple))
                and len(rate) == len(delta) == len(force)):
            raise ValueError("rate, force: with delta given as a list of collisions, must be "
                             "lists of the same length")
        runs = [(_as_array(f"delta[{i}]", d), _as_array(f"rate[{i}]", r),
                 _as_array(f"force[{i}]", f))
                for i, (d, r, f) in enumerate(zip(delta, rate, force))]
    else:
        runs = [(_as_array("delta", delta), _as_array("rate", rate), _as_array("force", force))]
    out = []
    for d, r, f in runs:
        if not len(d) == len(r) == len(f):
            raise ValueError(f"delta, rate, force: must have the same length, got {len(d)}, "
                             f"{len(r)}, {len(f)}")
        inside = d > 0
        edges = np.flatnonzero(np.diff(np.concatenate(([0], inside.astype(np.int8), [0]))))
        for i0, i1 in zip(edges[::2], edges[1::2]):
            if i1 - i0 < min_samples:
                continue
            v0 = _onset_rate(d, r, i0)
            if not v0 > 0:
                continue  # a run that does not start by moving into the stop
            out.append(Collision(d[i0:i1].copy(), r[i0:i1].copy(), f[i0:i1].copy(), v0))
    if not out:
        n_in = sum(int(np.sum(d > 0)) for d, _, _ in runs)
        if n_in == 0:
            raise ValueError("delta: no sample is in contact (delta > 0 nowhere): check the sign "
                             "convention (penetration is positive) or the column")
        raise ValueError(f"delta: no collision has at least min_samples = {min_samples} samples "
                         f"in contact with a positive onset rate ({n_in} samples in contact in "
                         "all): sample faster")
    return out


def _peak(c):
    """(delta, F) at the maximum indentation (delta' = 0, linear interpolation)."""
    r = c.rate
    k = np.flatnonzero((r[:-1] > 0) & (r[1:] <= 0))
    if len(k) == 0:
        i = int(np.argmax(c.delta))
        return float(c.delta[i]), float(c.force[i])
    i = int(k[0])
    w = r[i] / (r[i] - r[i + 1])
    d = c.delta[i] + w * (c.delta[i + 1] - c.delta[i])
    f = c.force[i] + w * (c.force[i + 1] - c.force[i])
    return float(d), float(f)


def _loop(x, y):
    """Closed-loop integral of y dx along the samples, closed at delta = 0 on both ends."""
    xx = np.concatenate(([0.0], x, [0.0]))
    yy = np.concatenate(([0.0], y, [0.0]))
    return float(np.sum(0.5 * (yy[1:] + yy[:-1]) * np.diff(xx)))


def _mean_se(v):
    v = np.asarray(v, dtype=float)
    return float(np.mean(v)), (float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1
                               else None)


def _paper(cs, law):
    peaks = np.array([_peak(c) for c in cs])
    dp, fp = peaks[:, 0], peaks[:, 1]
    if np.any(dp <= 0):
        raise ValueError("delta: a collision has no positive maximum indentation")
    K_each = fp / dp ** 1.5
    K, se_K = _mean_se(K_each)
    mu_each, e_each = [], []
    for c in cs:
        energy = _loop(c.delta, c.force)                      # Delta T (J), eq. 5
        denom = _loop(c.delta, c.delta ** 1.5 * c.rate)
        mu = energy / denom
        mu_each.append(mu)
        arg = 1.0 - 4.0 * mu * c.rate_onset / (3.0 * K)
        e_each.append(math.sqrt(arg) if arg > 0 else 0.0)
    mu, se_mu = _mean_se(mu_each)
    rates = np.array([c.rate_onset for c in cs])
    if law == "hertz":
        e = se_e = mu = se_mu = None
    elif law == "hunt-crossley":
        e = float(np.sqrt(max(0.0, 1.0 - 4.0 * mu * np.mean(rates) / (3.0 * K))))
        se_e = None
    else:
        e, se_e = _mean_se(e_each)
        mu = se_mu = None
    return K, se_K, e, se_e, mu, se_mu


def _design(cs, law):
    d15 = np.concatenate([c.delta ** 1.5 for c in cs])
    if law == "hertz":
        return d15[:, None]
    if law == "hunt-crossley":
        return np.column_stack([d15, d15 * np.concatenate([c.rate for c in cs])])
    q = np.concatenate([c.rate / c.rate_onset for c in cs])
    return np.column_stack([d15, d15 * q])


def _least_squares(cs, law):
    X = _design(cs, law)
    F = np.concatenate([c.force for c in cs])
    n, p = X.shape
    if n <= p + 1:
        raise ValueError(f"delta: {n} samples in contact are too few to fit {p} parameters")
    s = np.max(np.abs(X), axis=0)
    s[s == 0] = 1.0
    Xs = X / s
    coef, *_ = np.linalg.lstsq(Xs, F, rcond=None)
    res = F - Xs @ coef
    bread = np.linalg.inv(Xs.T @ Xs)
    meat = (Xs * (res ** 2)[:, None]).T @ Xs
    cov = bread @ meat @ bread * n / (n - p) / np.outer(s, s)
    coef = coef / s
    se = np.sqrt(np.diag(cov))
    K, se_K = float(coef[0]), float(se[0])
    e = se_e = mu = se_mu = None
    if law == "lankarani-nikravesh":
        c = coef[1] / K                                      # 3 (1 - e^2) / 4
        arg = 1.0 - 4.0 * c / 3.0
        e = math.sqrt(arg) if arg > 0 else 0.0
        # delta method: e = sqrt(1 - 4 b / (3 K)), gradient over (K, b)
        if e > 0:
            g = np.array([2.0 * coef[1] / (3.0 * K * K), -2.0 / (3.0 * K)]) / e
            se_e = float(math.sqrt(g @ cov @ g))
    elif law == "hunt-crossley":
        mu, se_mu = float(coef[1]), float(se[1])
        rate = float(np.mean([c.rate_onset for c in cs]))
        arg = 1.0 - 4.0 * mu * rate / (3.0 * K)
        e = math.sqrt(arg) if arg > 0 else 0.0
    return K, se_K, e, se_e, mu, se_mu


def identify_contact(delta, rate, force, *, law="lankarani-nikravesh", method="least-squares",
                     min_samples=MIN_SAMPLES):
    """Estimate the contact law's parameters from measured collisions (module docstring).

    delta (m), rate = delta' (m/s), force (N): one record of 1-D arrays, or lists of arrays
    (one per collision). law: 'hertz', 'lankarani-nikravesh' or 'hunt-crossley'; method:
    'least-squares' or 'paper'. Returns a ``ContactFit``.
    """
    choice("law", law, LAWS)
    choice("method", method, METHODS)
    if isinstance(min_samples, bool) or not isinstance(min_samples, (int, np.integer)):
        raise ValueError(f"min_samples: must be an integer >= 3, got {min_samples!r}")
    if min_samples < 3:
        raise ValueError(f"min_samples: must be an integer >= 3, got {min_samples!r}")
    cs = collisions(delta, rate, force, min_samples=int(min_samples))
    fmax = max(float(np.max(np.abs(c.force))) for c in cs)
    positive("force", fmax, unit="N (the largest contact force: the force column is all zero)")
    est = _paper(cs, law) if method == "paper" else _least_squares(cs, law)
    K, se_K, e, se_e, mu, se_mu = est
    if not K > 0:
        raise ValueError(f"force: the fitted K_hertz = {K:.3g} N/m^1.5 is not positive: is the "
                         "force positive in contact (pushing out of the stop)?")
    rates = np.array([c.rate_onset for c in cs])
    fit = ContactFit(law, method, K, e, mu, se_K, se_e, se_mu, 0.0, len(cs),
                     int(sum(len(c.delta) for c in cs)), rates)
    res = np.concatenate([c.force - fit.force(c.delta, c.rate, c.rate_onset) for c in cs])
    return ContactFit(law, method, K, e, mu, se_K, se_e, se_mu,
                      float(np.sqrt(np.mean(res ** 2))), len(cs), fit.n_samples, rates)
