"""The extended shooting system of a bifurcation in two parameters (frequency and a second one).

Unknowns, scaled: z = [u / scale_u, log f, q, (phase)], u the shooting states, f the excitation
frequency (Hz), q the second parameter (log of the amplitude, or value / |start value| for a
model parameter), phase (grazing only) the excitation phase (periods) of the grazing contact.
Equations: the shooting residual R(u, f, p) = 0 and

- fold, period doubling, Neimark-Sacker: g = 0, with g the bordered test function of
  A = M - I, M + I or C2(M) - I (M the monodromy, C2 its second compound matrix, whose
  eigenvalues are the products mu_i mu_j, i < j): [[A, b], [c^T, 0]] [v; g] = [0; 1], which
  vanishes exactly where A is singular and is regular there (a minimally augmented system;
  b and c are renewed from A's singular vectors at every accepted curve point);
- grazing: delta_e = 0 and d(delta_e)/dt = 0 at the grazing phase (the orbit touches stop e with
  zero relative velocity).

dR/du comes from the shooting problem (variational equations); dR/df and dR/dq by forward
differences; the row of g by forward differences, one monodromy per unknown, except, for a
fold or period doubling, over the shooting states: all of those from one monodromy, evaluated
with the states moved along the bordered system's right vector (CurveSystem._g_row_states);
the rows of the grazing conditions by forward differences (one flow per unknown). When the
monodromy is the exact derivative of the discrete map, Newton on this system converges
quadratically; it converges linearly (fast) otherwise.
"""
from __future__ import annotations

import copy
import dataclasses
import itertools
import math

import numpy as np

from nlbeam.parameters import get_parameter, with_parameter

from nlbeam import _linalg as la
from ._newton import ConvergenceError
from .shooting import _problem_from_state, event_elements

KINDS = ("fold", "period-doubling", "neimark-sacker", "grazing")
#: the gap lift (relative to the orbit's size) of the free-side multipliers on a grazing curve
LIFT = 1e-6
_CODIM2_NAME = {"fold": "fold-grazing", "period-doubling": "flip-grazing",
                "neimark-sacker": "neimark-sacker-grazing"}


def compound2(M):
    """The second compound matrix of M (n, n): its 2x2 minors, (n(n-1)/2, n(n-1)/2)."""
    n = len(M)
    pairs = list(itertools.combinations(range(n), 2))
    C = np.empty((len(pairs), len(pairs)))
    for a, (i, j) in enumerate(pairs):
        for b, (k, l) in enumerate(pairs):
            C[a, b] = M[i, k] * M[j, l] - M[i, l] * M[j, k]
    return C


def singular_matrix(kind, M):
    """The matrix that is singular at a bifurcation of this kind of the orbit of monodromy M."""
    if kind == "fold":
        return M - np.eye(len(M))
    if kind == "period-doubling":
        return M + np.eye(len(M))
    C = compound2(M)
    return C - np.eye(len(C))


def _bordered_system(A, b, c):
    """(K, rhs): the bordered matrix [[A, b], [c^T, 0]] and the right-hand side [0; 1]."""
    n = len(A)
    K = np.zeros((n + 1, n + 1))
    K[:n, :n] = A
    K[:n, n] = b
    K[n, :n] = c
    rhs = np.zeros(n + 1)
    rhs[n] = 1.0
    return K, rhs


def bordered(A, b, c):
    """The bordered test function g of A: zero exactly where A is singular (b, c: vectors
    not orthogonal to A's left and right null vectors there)."""
    K, rhs = _bordered_system(A, b, c)
    return float(la.solve(K, rhs)[-1])


def bordered_vectors(A, b, c):
    """(g, v, w): the bordered test function of A (``bordered``) with the right vector v and
    the left vector w of its bordered system ([[A, b], [c^T, 0]] [v; g] = [0; 1] and the
    transposed system for w), so that g's derivative in a change dA of A is -w^T dA v."""
    n = len(A)
    K, rhs = _bordered_system(A, b, c)
    x = la.solve(K, rhs)
    y = la.solve(np.ascontiguousarray(K.T), rhs)
    return float(x[n]), x[:n], y[:n]


def borders(A):
    """(b, c): the left and right singular vectors of A's smallest singular value."""
    return la.smallest_singular_vectors(A)


@dataclasses.dataclass
class GrazingCandidate:
    """An extremum of a stop's penetration over an orbit: score (its distance from zero
    relative to the orbit's size, plus for a maximum inside a contact the approach velocity
    of that contact relative to the orbit's velocity scale), element, phase (excitation
    periods), side ('touch': a maximum, touching from outside; 'lift-off': a minimum, a
    contact barely lifting off)."""

    score: float
    element: int
    phase: float
    side: str


def nearest_grazing(prob, u0, f, elements, phase=None):
    """The GrazingCandidate of the orbit u0 (shooting states of prob at frequency f Hz) closest
    to grazing over the stops ``elements`` (with ``phase``: the extremum nearest that
    excitation phase, periods), or None (no extremum)."""
    tr = prob.trajectory(u0, f)
    model, ex = prob.forcing(f)
    _, w, wy, gap = model.element_geometry()
    y, yd = ex.evaluate(tr.t)
    cands = []
    a = max(float(np.max(np.abs(tr.x))), 1e-300)
    v_scale = a * 2 * np.pi * f / prob.order
    for e in elements:
        d = la.matmul(tr.x, w[e]) + wy[e] * y - gap[e]
        dd = la.matmul(tr.v, w[e]) + wy[e] * yd
        dc = d[:-1]  # one period, periodic
        k = np.nonzero((dc >= np.roll(dc, 1)) & (dc > np.roll(dc, -1)))[0]
        for i in k:
            # a maximum inside a contact (d > 0) is a grazing contact only if the
            # contact began with a small approach velocity: an impact's peak penetration
            # is tiny under a stiff contact law, but its approach velocity is not
            score = abs(dc[i]) / a
            if dc[i] > 0:
                j = i
                while j > i - len(dc) and dc[j % len(dc)] > 0:
                    j -= 1
                score += abs(dd[(j + 1) % len(dc)]) / v_scale
            cands.append(GrazingCandidate(score, e, tr.t[i] * f, "touch"))
        # a minimum near zero: a sustained contact that barely lifts off (or a separation
        # that barely reaches the stop again), as in the paper model's chattering orbits
        # below 9.1 Hz, whose impact peaks (maxima) lie 1e-3 of the orbit's size in
        # contact while the grazing minimum is 1e-5 from zero
        kmin = np.nonzero((dc <= np.roll(dc, 1)) & (dc < np.roll(dc, -1)))[0]
        for i in kmin:
            cands.append(GrazingCandidate(abs(dc[i]) / a, e, tr.t[i] * f, "lift-off"))
    if not cands:
        return None
    if phase is None:
        return min(cands, key=lambda c: c.score)
    n = prob.order
    return min(cands, key=lambda c: abs((c.phase - phase + 0.5 * n) % n - 0.5 * n))


class CurveState:
    """What is known at one point of the extended system's solution set: z, G, J (dG/dz
    (D - 1, D), scaled; None if not computed), multipliers (computed when first read: the
    corrector's iterates never need them), xmax (m), n_impacts."""

    def __init__(self, z, G, J, multipliers, xmax, n_impacts):
        self.z, self.G, self.J = z, G, J
        self._mu = multipliers  # an array, None, or a callable giving one
        self.xmax, self.n_impacts = xmax, n_impacts

    @property
    def multipliers(self):
        if callable(self._mu):
            self._mu = self._mu()
        return self._mu


class CurveSystem:
    """The extended system G(z) = 0 (D - 1 equations, D unknowns) of one bifurcation kind of
    the orbits of one order; module doc. parameter: 'amplitude' or any name of
    nlbeam.parameters ('e', 'K_hertz', 'b', 'elements[0].gap', ...)."""

    def __init__(self, model, kind, order, amplitude, frequency, state0, parameter, integrator, *,
                 disc0=None, segments=1, element=None, phase=None):
        self.kind = kind
        self.order = int(order)
        self.parameter = parameter
        self.model0 = model
        self.amplitude0 = float(amplitude)
        self.prob, u0 = _problem_from_state(model, amplitude, frequency, order, state0, segments,
                                            integrator, disc0=disc0)
        p0 = self.amplitude0 if parameter == "amplitude" else get_parameter(model, parameter)
        self.log_p = parameter == "amplitude" or p0 > 0
        self.p_scale = 1.0 if self.log_p else max(abs(p0), 1.0)
        self._model_cache = (p0, model)
        self.n = self.prob.n
        self.grazing = kind == "grazing"
        self.D = self.n + 2 + (1 if self.grazing else 0)
        self.n_evaluations = 0
        self._last = None  # (problem, z bytes, with monodromy, Evaluation): _evaluate
        # the fold / period-doubling row over the states from one evaluation (_g_row_states);
        # False: one difference per state (the tracer's fallback where a step fails)
        self.row_from_one = True
        self.one_row_kind = kind in ("fold", "period-doubling")  # the others: differences
        z = np.r_[u0 / self.prob.scale_u, math.log(frequency), self.q_of(p0)]
        if self.grazing:
            self.element, phase = self._grazing_start(u0, frequency, p0, element, phase)
            z = np.r_[z, phase]
        else:
            M = self._monodromy(z)[0]
            self.b, self.c = borders(singular_matrix(kind, M))
        self.z0 = z

    # --- parameters ----------------------------------------------------------------------------
    def q_of(self, p):
        return math.log(p) if self.log_p else p / self.p_scale

    def p_of(self, q):
        return math.exp(q) if self.log_p else q * self.p_scale

    def _set(self, p):
        """Put the second parameter's value p into the shooting problem."""
        prob = self.prob
        if self.parameter == "amplitude":
            prob.amplitude = float(p)
            return
        key, m = self._model_cache
        if key != p:
            m = with_parameter(self.model0, self.parameter, float(p))
            self._model_cache = (p, m)
        prob.base_model = m

    def unpack(self, z):
        """(u, f Hz, p) of the scaled unknowns z."""
        return z[:self.n] * self.prob.scale_u, math.exp(z[self.n]), self.p_of(z[self.n + 1])

    def point(self, z):
        """(frequency Hz, second parameter value) of z."""
        return math.exp(z[self.n]), self.p_of(z[self.n + 1])

    # --- pieces --------------------------------------------------------------------------------
    def _evaluate(self, z, jac):
        """The shooting evaluation at z: R, with jac dR/du and the monodromy (no dR/df). The
        last one is kept and given again for the same z and problem (the corrector's last
        iterate is where the point's Jacobian and the new borders are evaluated next)."""
        u, f, p = self.unpack(z)
        self._set(p)
        key = z.tobytes()
        last = self._last
        if last is not None and last[0] is self.prob and last[1] == key and (last[2] or not jac):
            return last[3]
        self.n_evaluations += 1
        ev = self.prob.evaluate(u, f, jac=jac, jac_p=False)
        self._last = (self.prob, key, jac, ev)
        return ev

    def _monodromy(self, z):
        ev = self._evaluate(z, True)
        return self.prob.monodromy(ev.Ms), ev

    def _g(self, z):
        M, _ = self._monodromy(z)
        return bordered(singular_matrix(self.kind, M), self.b, self.c)

    def _grazing_state(self, z):
        """(delta, d delta / dt) of the grazing element at the grazing phase (m, m/s)."""
        u, f, p = self.unpack(z)
        self._set(p)
        prob = self.prob
        model, ex = prob.forcing(f)
        U = u.reshape(prob.n_seg, prob.N2)
        b = prob.boundaries
        ph = b[0] + (z[-1] - b[0]) % prob.order
        j = int(np.searchsorted(b, ph, side="right") - 1)
        dphi = ph - b[j]
        s = U[j] if dphi < 1e-14 else prob.flow_phases(model, ex, U[j], b[j], dphi,
                                                        newton=True).state
        self.n_evaluations += 1
        _, w, wy, gap = model.element_geometry()
        e = self.element
        N = model.n_dof
        y, yd = ex.evaluate(ph / f)
        return (float(la.dot(w[e], s[:N]) + wy[e] * y[0] - gap[e]),
                float(la.dot(w[e], s[N:]) + wy[e] * yd[0]))

    def _grazing_rows(self, z):
        u, f, p = self.unpack(z)
        a = self.prob.scale_u[0]
        om = 2 * np.pi * f / self.order
        d, dd = self._grazing_state(z)
        return np.array([d / a, dd / (a * om)])

    def _grazing_start(self, u0, f, p, element, phase):
        """(element, phase): the stop and excitation phase (periods) of the extremum of the
        penetration closest to zero over the orbit (a maximum touching from outside, a
        minimum lifting off from inside a contact; given ones are checked and kept)."""
        prob = self.prob
        self._set(p)
        idx = event_elements(prob.base_model)
        if not idx:
            raise ValueError("kind: 'grazing' needs a model with a contact element (a stop)")
        if element is not None and element not in idx:
            raise ValueError(f"element: must be one of the stops {idx}, got {element!r}")
        best = nearest_grazing(prob, u0, f, [element] if element is not None else idx, phase)
        if best is None:
            raise ConvergenceError("grazing: the orbit has no extremum of the penetration; "
                                   "give phase= (excitation periods) of the grazing contact")
        self.grazing_side = best.side
        return best.element, best.phase if phase is None else float(phase)

    def start_failure(self, exc):
        """A ConvergenceError whose message says why the start (the curve's first point) did
        not converge and what to try, from the start orbit (exc: the corrector's error)."""
        where = f"{self.kind} curve (order {self.order}): the start did not converge ({exc})"

        def failure(advice):
            err = ConvergenceError(f"{where}. {advice}")
            err.advice = advice  # the same for every start that fails the same way
            return err

        u0, f0, p0 = self.unpack(self.z0)
        self._set(p0)
        if self.grazing:
            if getattr(self, "grazing_side", "") == "lift-off":
                return failure(
                    "Its grazing contact is a lift-off: a minimum of the penetration "
                    "inside a sustained (chattering) contact barely reaching zero, where a new "
                    "contact may begin at once; a law with memory (Lankarani-Nikravesh: the "
                    "onset velocity) resets there, so the shooting map jumps (the paper model "
                    "near 9.19 Hz: 1.8e-3 for a 1.4e-8 move of the state) and the grazing "
                    "condition has no smooth solution to converge to. Try: phase= "
                    "(excitation periods) of another extremum of the penetration; or the "
                    "folds and period doublings of this region (their curves bound the same "
                    "regions of the chart); or a diagram at another amplitude, where the "
                    "grazing contact may be a clean touch")
            return failure(
                "Try element= / phase= (excitation periods) of the grazing contact, "
                "or a diagram point farther from other grazing points")
        g = nearest_grazing(self.prob, u0, f0, event_elements(self.prob.base_model))
        if g is not None and g.score < 1e-3:
            return failure(
                f"The start orbit grazes stop {g.element} (its penetration's "
                f"{'minimum' if g.side == 'lift-off' else 'maximum'} at phase "
                f"{g.phase:.6g} periods is {g.score:.1e} of the orbit's size from zero): the "
                f"{self.kind} lies at (or closer than the corrector can separate from) a "
                "grazing point, where the shooting map is not smooth. Trace the grazing curve "
                "instead (from the diagram's grazing point next to it, a Bifurcation of kind "
                "'grazing'; or an orbit solved at its frequency): its points carry the "
                f"multipliers, and its special points ('{_CODIM2_NAME[self.kind]}') mark "
                "where this curve leaves it; or start from this bifurcation "
                "in a diagram at another amplitude, where it lies away from the grazing")
        return failure(
            "Try segments=4 (multiple shooting), a smaller step (dt_scale=0.5), "
            "or a start located more precisely (accuracy='high' in the diagram)")

    # --- the system ----------------------------------------------------------------------------
    def evaluate(self, z, jac=True):
        """A CurveState at z: G (D - 1,) and (with jac) its Jacobian (D - 1, D), scaled.
        dR/du from the variational equations; every other column by forward differences
        (step 1e-6 in the scaled unknowns): one evaluation with the monodromy per unknown
        gives the test function's row and, for frequency and parameter, dR/df and dR/dq;
        for a fold or period doubling the row's entries over the shooting states come from
        one evaluation (_g_row_states), so a Jacobian costs 3 evaluations, not n + 2
        (grazing: one flow to the grazing phase per unknown, and two shooting evaluations)."""
        n, D = self.n, self.D
        w = self.prob.scale_u
        if self.grazing and not jac:
            # the grazing equations need no monodromy: the flow alone (the multipliers, when
            # read, from their own evaluation)
            ev = self._evaluate(z, False)
            mu = self._multipliers_of(z, None)
        else:
            ev = self._evaluate_full(z)
            mu = self._multipliers_of(z, ev) if ev.Ms else None
        if self.grazing:
            extra = self._grazing_rows(z)
        else:
            M = self.prob.monodromy(ev.Ms)
            extra = np.array([bordered(singular_matrix(self.kind, M), self.b, self.c)])
        G = np.r_[ev.R / w, extra]
        if not jac:
            return CurveState(z.copy(), G, None, mu, float(ev.xmax), int(ev.n_impacts))
        J = np.zeros((D - 1, D))
        J[:n, :n] = ev.Ju * w[None, :] / w[:, None]
        h = 1e-6
        columns = range(D)
        if self.row_from_one and self.one_row_kind and ev.Ms:
            # the test function's row in the shooting states from one evaluation
            J[n, :n] = self._g_row_states(z, ev, h)
            columns = (n, n + 1)
        for i in columns:
            zp = z.copy()
            zp[i] += h
            if self.grazing:
                J[n:, i] = (self._grazing_rows(zp) - extra) / h
                if i in (n, n + 1):
                    J[:n, i] = (self._evaluate(zp, False).R - ev.R) / (h * w)
                continue
            Mp, evp = self._monodromy(zp)
            J[n, i] = (bordered(singular_matrix(self.kind, Mp), self.b, self.c) - extra[0]) / h
            if i in (n, n + 1):
                J[:n, i] = (evp.R - ev.R) / (h * w)
        self._last = (self.prob, z.tobytes(), True, ev)  # the point's, not the last column's
        return CurveState(z.copy(), G, J, mu, float(ev.xmax), int(ev.n_impacts))

    def _g_row_states(self, z, ev, h):
        """dg/dz over the scaled shooting states (n,) of a fold or period-doubling test
        function g, from ONE more evaluation with the monodromies instead of one per state.
        g's derivative is -w^T dM v (bordered_vectors; dM = dA for M -+ I). With
        M = M_{m-1} ... M_0 (segment j's M_j a function of its start U_j only),
        dg/dU_j,i = -w_j^T (dM_j/dU_j,i) v_j, w_j = (M_{m-1} ... M_{j+1})^T w,
        v_j = M_{j-1} ... M_0 v; and (dM_j/dU_j,i) v_j = (dM_j[v_j]) e_i, the derivative of
        M_j along v_j (the second derivatives of a smooth flow are symmetric), which one
        evaluation with every U_j moved along its v_j gives by a forward difference (largest
        move h in the scaled states, as the columns' differences)."""
        n, N2 = self.n, self.prob.N2
        w = self.prob.scale_u
        Ms = list(ev.Ms)
        M = self.prob.monodromy(Ms)
        _, v, wl = bordered_vectors(singular_matrix(self.kind, M), self.b, self.c)
        m = len(Ms)
        vs, ws = [], [None] * m
        x = v
        for j in range(m):
            vs.append(x)
            x = la.matmul(Ms[j], x)
        y = wl
        for j in range(m - 1, -1, -1):
            ws[j] = y
            y = la.matmul(np.ascontiguousarray(Ms[j].T), y)
        d = np.concatenate(vs)
        big = float(np.max(np.abs(d / w)))
        if not big > 0:
            return np.zeros(n)
        s = h / big
        zp = z.copy()
        zp[:n] = z[:n] + s * d / w
        Mp = list(self._evaluate(zp, True).Ms)
        row = np.empty(n)
        for j in range(m):
            dM = (Mp[j] - Ms[j]) / s
            row[j * N2:(j + 1) * N2] = -la.matmul(dM.T.copy(), ws[j])
        return row * w

    def _multipliers_of(self, z, ev):
        """A callable: the multipliers at z (ev: its evaluation). On a grazing curve of a
        touching contact (a maximum of the penetration at zero), those of the limit from
        the free side: the integrator may see a contact of depth ~ the corrector's
        tolerance at the tangent peak, whose contact phase spoils the monodromy (measured
        on a stiff piecewise-linear stop: 5e-6, up to 5e-2 at some points); so the
        monodromy along the orbit is taken with the stop's gap lifted by LIFT and 2 LIFT of
        the orbit's size, and extrapolated linearly to no lift (two more evaluations)."""
        prob = self.prob
        name = self._lift_name() if self.grazing and self.grazing_side == "touch" else None
        if name is None:
            if ev is None:
                return lambda: prob.multipliers(self._evaluate(z, True).Ms)
            return lambda: prob.multipliers(ev.Ms)
        u, f, p = self.unpack(z)

        def lifted():
            from ._floquet import multipliers

            self._set(p)
            Ms = []
            for k in (1, 2):
                lp = copy.copy(prob)
                lp._fm = None
                lp._cache = (None, None)
                g = get_parameter(prob.base_model, name)
                lp.base_model = with_parameter(prob.base_model, name,
                                               g + k * LIFT * prob.scale_u[0])
                self.n_evaluations += 1
                Ms.append(lp.evaluate(u, f, jac=True, jac_p=False).Ms)
            return multipliers([2 * a - b for a, b in zip(*Ms)])

        return lifted

    def _lift_name(self):
        """The parameter name of the grazing stop's gap, or None (no such parameter)."""
        from nlbeam.parameters import parameter_names

        names = parameter_names(self.prob.base_model)
        for name in (f"elements[{self.element}].gap", "gap"):
            if name in names and (name != "gap" or len(event_elements(self.prob.base_model))
                                  == 1):
                return name
        return None

    def _evaluate_full(self, z):
        """The shooting evaluation at z with the monodromy (dR/du)."""
        return self._evaluate(z, True)

    def snapshot(self):
        """What restore() needs to put the system back (the problem may be renewed by adapt)."""
        return (self.prob, self.n, self.D, getattr(self, "b", None), getattr(self, "c", None),
                self.z0)

    def restore(self, snap):
        self.prob, self.n, self.D, self.b, self.c, self.z0 = snap
        self._last = None

    def renew_borders(self, z):
        """New bordering vectors at z (keeps the bordered matrix well conditioned)."""
        if not self.grazing:
            M = self._monodromy(z)[0]
            self.b, self.c = borders(singular_matrix(self.kind, M))

    def adapt(self, z):
        """None, or z in a renewed shooting problem (boundaries moved out of contact, step
        level changed, scales renewed) when the orbit at z asks for it."""
        u, f, p = self.unpack(z)
        self._set(p)
        new = self.prob.adapt(u, f)
        if new is None:
            return None
        self._last = None
        tail = z[self.n:]
        self.prob, u2 = new
        self.n = self.prob.n
        z2 = np.r_[u2 / self.prob.scale_u, tail]
        self.D = len(z2)
        self.renew_borders(z2)
        return z2

    def state_at_zero(self, z):
        u, f, p = self.unpack(z)
        self._set(p)
        return self.prob.state_at_zero(u, f)
