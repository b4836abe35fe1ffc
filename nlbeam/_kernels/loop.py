"""The integration loop: ``integrate_kernel`` from t0 to t_end with exact contact events,
graded contact steps, dense-output samples and the monodromy."""
import math

import numpy as np

from .bundles import Outputs, Settings, Start, SystemArrays, Work
from .codes import DP5, ERR_MAX_STEPS, ERR_STEP_UNDERFLOW, PWL_STOP, RK2, RK4, VMINUS_FLOOR
from .contact import (contact_rate, contact_rate_sens, contact_step, contact_step_sens,
                      grade_multiple)
from .events import _crossing, _may_cross, delta_extremum, locate
from .events_sens import boundary_time_sens, dsw_sens, onset_sens
from .excite import excite
from .field import deriv, deriv_plain, has_event, kinematics
from .graded import rk_step_graded
from .hook import _HAS_USER, njit
from .routine import routine_steps
from .samples import _store, grid_samples, track_xmax_step
from .sens_steps import (SE_DSW, SE_DTC, SE_DTN, SE_ROWS, SR_DSC, SR_GEND, SR_GH, SR_H, SR_ROWS,
                         SR_T, SR_TN, SR_TREF, SR_U0, rk_step_sens, step_length_derivative,
                         var_time_step)
from .steps import _rk_step_plain, _rk_step_var, rk_step_free, rk_step_with_var, tableau


_WANT_VAR = Settings._fields.index("want_var")


def integrate_kernel(system, xc, xp, xtab, settings, start, outputs):
    """Integrate from t0 to t_end (``integrate_var`` when the settings ask for the variational
    equations, else ``integrate_plain``; a Python function: each of the two compiled kernels
    compiles, or loads from the disk cache, only when first called: a process that never asks
    for a monodromy never compiles the variational loop: the plain one compiles in about
    49 s CPU, the variational one 64 s more, `benchmarks/kernel_compile.py`).
    ``system``, ``settings``, ``start`` and ``outputs`` are the fields of SystemArrays,
    Settings, Start and Outputs (bundles.py), (xc, xp, xtab) the excitation. Returns the
    status."""
    kernel = integrate_var if settings[_WANT_VAR] else integrate_plain
    return kernel(system, xc, xp, xtab, settings, start, outputs)


@njit(cache=True, _nrt=True)
def integrate_plain(system, xc, xp, xtab, settings, start, outputs):
    """integrate_kernel without the variational equations (the settings' want_var is not
    read)."""
    sysa, cfg, out, work = _bundles(system, settings, start, outputs)
    return _loop_plain(sysa, xc, xp, xtab, cfg, out, work)


@njit(cache=True, _nrt=True)
def integrate_var(system, xc, xp, xtab, settings, start, outputs):
    """integrate_kernel with the variational equations (the settings' want_var is not read)."""
    sysa, cfg, out, work = _bundles(system, settings, start, outputs)
    return _loop_var(sysa, xc, xp, xtab, cfg, out, work)


@njit(cache=True, _nrt=True, inline="always")
def _bundles(system, settings, start, outputs):
    """The bundles of an integration and its work arrays, allocated here: (SystemArrays,
    Settings, Outputs, Work). Inlined into each kernel (a dispatcher level of its own around
    the loop cost 5-13 s CPU more to compile)."""
    sysa = SystemArrays(*system)
    cfg = Settings(*settings)
    st0 = Start(*start)
    N = sysa.MinvK.shape[0]
    n = 2 * N
    ne = sysa.etype.shape[0]
    m = st0.P0.shape[1]
    A, B, BH, Cc = tableau(cfg.meth)
    ns = B.shape[0]
    KS = np.zeros((ns, n))
    KP = np.zeros((ns, n, m))
    KT = np.zeros(ns)
    ytmp = np.zeros(n)
    Ptmp = np.zeros((n, m))
    fel = np.zeros(ne)
    err_w = np.zeros(n)
    s = st0.s0.copy()
    P = st0.P0.copy()
    dvm = st0.dvm0.copy()
    disc = st0.disc0.copy()
    s_new = np.zeros(n)
    P_new = np.zeros((n, m))
    s_try = np.zeros(n)
    f0 = np.zeros(n)
    f1 = np.zeros(n)
    dummyP = np.zeros((n, m))
    steps_in_contact = np.zeros(ne, dtype=np.int64)
    # a contact under way at t0 started before this call: its steps here are not all of its
    # steps, so it does not enter the steps-per-contact count
    from_before = np.zeros(ne, dtype=np.bool_)
    dtc = np.full(ne, np.inf)
    d_sw = np.full(ne, -1.0)     # delta at which the graded exit phase starts (-1: unknown)
    work = Work(KS=KS, KP=KP, KT=KT, ytmp=ytmp, Ptmp=Ptmp, fel=fel, err_w=err_w, s=s, P=P,
                dvm=dvm, disc=disc, s_new=s_new, P_new=P_new, s_try=s_try, dummyP=dummyP, f0=f0,
                f1=f1, steps_in_contact=steps_in_contact, from_before=from_before, dtc=dtc,
                d_sw=d_sw, dtn=np.full(ne, np.inf), SR=np.zeros((SR_ROWS, m)),
                SE=np.zeros((SE_ROWS, ne, m)), ft=np.zeros(n), W1=np.zeros((4, max(n, ne), 1)),
                KP1=np.zeros((ns, n, 1)), SR1=np.zeros((SR_ROWS, 1)), Bv=np.zeros(n))
    return sysa, cfg, Outputs(*outputs), work


def _loop_for(want_var):
    """The integration loop, with (``want_var`` True) or without the variational equations:
    ``_integrate_loop(sysa, xc, xp, xtab, cfg, out, work)`` on the work arrays the kernel
    allocated (no reference counting here: see ``njit``). ``want_var`` is a constant of the
    closure, so numba prunes every branch on it before typing: the plain loop does not type
    or compile any variational step function, nor the variational loop the routine steps
    (with ``want_var`` an argument, even a literal one, numba typed both sides).

    Fixed-step methods (RK2, RK4) step on the grid t0 + k dt in free flight; inside a contact
    they take steps of min(dt, (estimated contact duration) / spc), starting from the onset and
    ignoring the grid (grid samples inside a contact come from the quintic Hermite dense
    output), so that the step sequence is a smooth function of the initial state. Every
    contact boundary is a root of the step map, landed on to a few ulps of t. With ``graded``
    (one element in contact) the first quarter of a contact is stepped uniformly in sigma =
    sqrt(t - t_onset), and from the point where delta has fallen back to KAPPA * (its maximum)
    uniformly in u = sqrt(delta) down to delta = 0 (then polished to round-off): this removes
    the delta^1.5 singularity of the contact force at both boundaries. No step of these phases
    lasts longer than dt either: n_grade * grade_multiple(dtn, dt) steps each (a power of 2 of
    dtn / dt, not a function of the state), over spans that do not depend on dt. DP5 controls
    its error with (rtol, atol); grid samples come from dense output. Samples: every
    store_every-th grid point, t0 and t_end included.
    With want_var, P, dvm and the rows of SR and SE carry the derivative of the map as
    computed: every step size and step time that depends on the state is differentiated too
    (sens_steps.py, events_sens.py)."""

    @njit(cache=True)
    def _integrate_loop(sysa, xc, xp, xtab, cfg, out, work):
        """The loop (``_loop_for``): the bundles' fields as local names, then the steps."""
        meth, t0, t_end, dt, spc = cfg.meth, cfg.t0, cfg.t_end, cfg.dt, cfg.spc
        rtol, atol, h_init, max_steps = cfg.rtol, cfg.atol, cfg.h_init, cfg.max_steps
        events_on, track_xmax = cfg.events_on, cfg.track_xmax
        store_every, graded = cfg.store_every, cfg.graded
        out_t, out_s, out_d, out_f, ev_log = out.t, out.s, out.delta, out.force, out.ev_log
        s_end, disc_end, P_end, dvm_end = out.s_end, out.disc_end, out.P_end, out.dvm_end
        xmax, counters, fcounters = out.xmax, out.counters, out.fcounters
        KS, KP, KT, ytmp, Ptmp, fel, err_w = (work.KS, work.KP, work.KT, work.ytmp, work.Ptmp,
                                              work.fel, work.err_w)
        s, P, dvm, disc, s_new, P_new = work.s, work.P, work.dvm, work.disc, work.s_new, work.P_new
        s_try, dummyP, f0, f1 = work.s_try, work.dummyP, work.f0, work.f1
        steps_in_contact, from_before, dtc, d_sw = (work.steps_in_contact, work.from_before,
                                                    work.dtc, work.d_sw)
        dtn, SR, SE, ft, Bv = work.dtn, work.SR, work.SE, work.ft, work.Bv
        W1, KP1, SR1 = work.W1, work.KP1, work.SR1
        KAPPA = 0.25
        etype = sysa.etype
        N = sysa.MinvK.shape[0]
        n = 2 * N
        ne = etype.shape[0]
        m = P.shape[1]
        A, B, BH, Cc = tableau(meth)
        ns = B.shape[0]
        y, yd, ydd, st = excite(t0, xc, xp, xtab)
        for e in range(ne):
            if disc[e, 0] != 0.0:
                from_before[e] = True
                # a record that starts inside a contact: the impact velocity with the same energy
                d, dd = kinematics(e, s, y, yd, sysa)
                winv = 0.0
                for j in range(N):
                    winv += sysa.ew[e, j] * sysa.mw[e, j]
                K = sysa.epar[e, 0]
                pot = 0.8 * K * max(d, 0.0) ** 2.5 if etype[e] != PWL_STOP else K * max(d, 0.0) ** 2
                v_eq = math.sqrt(dd * dd + pot * winv)
                dtn[e] = contact_step(e, v_eq, 0.0, sysa, spc)
                dtc[e] = min(dtn[e], dt)
                if want_var and dtn[e] < dt and v_eq > 0.0:
                    # the contact step is a function of the state at the start (P: its sensitivity)
                    cs, dcs_dv, dcs_da = contact_step_sens(e, v_eq, 0.0, sysa, spc)
                    dpot = 2.0 * K * (max(d, 0.0) ** 1.5 if etype[e] != PWL_STOP else max(d, 0.0))
                    for c in range(m):
                        dx = 0.0
                        dv = 0.0
                        for j in range(N):
                            dx += sysa.ew[e, j] * P[j, c]
                            dv += sysa.ew[e, j] * P[N + j, c]
                        SE[SE_DTC, e, c] = dcs_dv * (dd * dv + 0.5 * winv * dpot * dx) / v_eq

        # (counters passed to routine_steps typed int64 from the start, as phase and pe below)
        n_stored = np.int64(0)
        n_steps = np.int64(0)
        n_rej = 0
        n_rhs = np.int64(0)
        n_imp = 0
        min_spc = 1 << 62
        n_contacts = 0
        n_events = 0
        max_land = 0.0
        fixed = meth != DP5
        n_grade = max(2, int(spc // 4))
        k_grid = np.int64(0)
        n_grid = int(math.ceil((t_end - t0) / dt - 1e-9))
        t = t0
        h = h_init
        status = 0
        en = 1.0
        # (typed int64 from the start: numba's first typing pass would otherwise see the literals
        # 0 and -1 and compile a dead copy of every step function for them, ~1/4 of the compile)
        phase = np.int64(0)  # 0: time steps; 1: onset, steps in sigma; 2: exit, steps in u
        pe = np.int64(-1)    # the element of the graded phase
        row_t = np.int64(SR_T)    # the rows of SR a sensitive step writes (int64 as well: one
        row_tn = np.int64(SR_TN)  # compiled copy of rk_step_sens and var_time_step for both)
        g_t0 = 0.0
        g_u = 0.0
        g_end = 0.0
        g_h = 0.0
        t_dep = False   # with want_var: d t / d z (SR[SR_T]) may be nonzero
        sens_step = False
        # routine RK4 steps go to the lean loop of routine.py (the same doubles); after a call
        # that took no step, the general loop takes one before the next call
        routine = cfg.routine and meth == RK4 and not _HAS_USER
        skip_routine = False
        n_routine = 0

        st = deriv(t, s, P, dvm, disc, want_var, sysa, xc, xp, xtab, f0, KP[0], fel)
        n_rhs += 1
        if st != 0:
            return st
        if track_xmax:
            for i in range(N):
                xmax[i] = max(xmax[i], abs(s[i]))
        if store_every > 0 and out_t.shape[0] > 0:
            n_stored = _store(n_stored, t, s, disc, xc, xp, xtab, sysa, out_t, out_s, out_d, out_f)

        while t < t_end and status == 0:
            if n_steps >= max_steps:
                status = ERR_MAX_STEPS
                break
            if not want_var and routine and phase == 0:
                if skip_routine:
                    skip_routine = False
                else:
                    t, k_grid, n_steps, n_stored, n_rhs, n_r = routine_steps(
                        sysa, xc, xp, xtab, t0, t_end, dt, n_grid, max_steps, events_on, track_xmax,
                        graded, store_every, t, k_grid, n_steps, n_stored, n_rhs, s, f0, s_new, f1,
                        disc, dtc, d_sw, steps_in_contact, KS, ytmp, fel, xmax, out_t, out_s, out_d,
                        out_f)
                    n_routine += n_r
                    skip_routine = n_r == 0
                    if not t < t_end:
                        break
                    if n_steps >= max_steps:
                        status = ERR_MAX_STEPS
                        break
            n_in = 0
            for e in range(ne):
                if disc[e, 0] != 0.0:
                    n_in += 1
                    if phase == 0:
                        pe = e
            ev = np.int64(-1)   # (int64, not a literal: as phase and pe)
            tau_ev = 0.0
            hit_grid = False
            enter_exit = False
            sens_step = False   # the step's sensitivities of its end time are in SR[SR_TN]
            if phase == 2:
                y, yd, ydd, st = excite(t, xc, xp, xtab)
                d, dd = kinematics(pe, s, y, yd, sysa)
                if disc[pe, 0] == 0.0 or dd >= 0.0 or n_in != 1:
                    phase = 0
            if phase == 1 and n_in != 1:
                phase = 0
            if phase != 0:
                # a graded step longer than the stability limit of the contact law (a slow, stiff
                # contact): fall back to time steps, which respect it
                if phase == 1:
                    dt_est = (g_u + g_h) ** 2 - g_u ** 2
                else:
                    y, yd, ydd, st = excite(t, xc, xp, xtab)
                    d, dd = kinematics(pe, s, y, yd, sysa)
                    dt_est = 2.0 * g_u * g_h / max(-dd, 1e-300)
                if contact_rate(t, s, disc, sysa, xc, xp, xtab) * dt_est > 0.5:
                    phase = 0
            if phase == 1:
                # onset phase: uniform steps in sigma = sqrt(t - t_onset)
                hs = min(g_h, g_end - g_u)
                cut = False
                if g_t0 + (g_u + hs) ** 2 >= t_end:
                    hs = math.sqrt(t_end - g_t0) - g_u
                    cut = True
                if want_var:
                    # the step's own sensitivity: g_h, the remainder g_end - g_u, or up to t_end
                    for c in range(m):
                        if cut:
                            SR[SR_H, c] = (-SR[SR_TREF, c] / (2.0 * math.sqrt(t_end - g_t0))
                                           - SR[SR_U0, c])
                        elif hs == g_h:
                            SR[SR_H, c] = SR[SR_GH, c]
                        else:
                            SR[SR_H, c] = SR[SR_GEND, c] - SR[SR_U0, c]
                    st, t_new = rk_step_sens(meth, phase, g_u, hs, g_t0, pe, s, t, P, dvm, disc,
                                             sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT, ytmp,
                                             Ptmp, fel, ft, err_w, SR, row_t)
                    sens_step = True
                else:
                    # (mode = phase, 1 here: one compiled copy for both modes, as rk_step_sens)
                    st, t_new = rk_step_graded(meth, phase, g_u, hs, g_t0, pe, s, t, P, dvm, disc,
                                               False, sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT,
                                               ytmp, Ptmp, fel)
                n_rhs += ns
                if cut:
                    t_new = t_end
                    if want_var:
                        for c in range(m):
                            SR[SR_TN, c] = 0.0
                ok = st == 0
                if ok:
                    st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1, KP[0],
                               fel)
                    n_rhs += 1
                    yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                    for e in range(ne):
                        if has_event(etype[e]):
                            d, dd = kinematics(e, s_new, yv, ydv, sysa)
                            if (disc[e, 0] != 0.0 and d < 0.0) or (disc[e, 0] == 0.0 and d > 0.0):
                                ok = False
                if not ok:
                    phase = 0  # something happens inside the onset phase: fall back to time steps
                    continue
                g_u += hs
                if want_var:
                    for c in range(m):
                        SR[SR_U0, c] += SR[SR_H, c]
                if g_u >= g_end * (1.0 - 1e-12):
                    phase = 0
            elif phase == 2:
                # exit phase: uniform steps in u = sqrt(delta) down to u = 0
                hu = min(g_h, g_u)
                if g_u - hu < 1e-9 * g_h:
                    hu = g_u
                if want_var:
                    # the step -g_h, or the rest -g_u down to u = 0
                    for c in range(m):
                        SR[SR_H, c] = -SR[SR_U0, c] if hu == g_u else -SR[SR_GH, c]
                    st, t_new = rk_step_sens(meth, phase, g_u, -hu, 0.0, pe, s, t, P, dvm, disc,
                                             sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT, ytmp,
                                             Ptmp, fel, ft, err_w, SR, row_t)
                    sens_step = True
                else:
                    st, t_new = rk_step_graded(meth, phase, g_u, -hu, 0.0, pe, s, t, P, dvm, disc,
                                               False, sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT,
                                               ytmp, Ptmp, fel)
                n_rhs += ns
                if st != 0 or t_new > t_end or t_new <= t:
                    phase = 0  # the record ends inside the exit phase (or it failed): time steps
                    continue
                # the step in u is only valid while delta falls monotonically: if delta' reached 0
                # inside it (a slow contact held by the base), the state no longer has delta =
                # u^2 and delta' < 0; retake the step in time
                yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                d, dd = kinematics(pe, s_new, yv, ydv, sysa)
                u_new = g_u - hu
                if not (dd < 0.0 and abs(d - u_new * u_new) <= 0.05 * (g_u * g_u - u_new * u_new)):
                    phase = 0
                    continue
                g_u -= hu
                if want_var:
                    for c in range(m):
                        SR[SR_U0, c] += SR[SR_H, c]
                        SR[SR_H, c] = 0.0   # the polishing steps below: at fixed lengths
                st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1, KP[0],
                           fel)
                n_rhs += 1
                if g_u <= 0.0:
                    # landed on delta = 0 up to the truncation error: polish to round-off by Newton
                    # steps in time, then switch
                    for _ in range(4):
                        yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                        d, dd = kinematics(pe, s_new, yv, ydv, sysa)
                        if d == 0.0 or abs(d) <= 1e-15 * (abs(yv) + abs(sysa.egap[pe]) + 1e-300):
                            break
                        tau = -d / dd
                        for q in range(n):
                            s_try[q] = s_new[q]
                            if want_var:
                                for c in range(m):
                                    dummyP[q, c] = P_new[q, c]
                        if want_var:
                            st = var_time_step(meth, t_new, tau, s_try, dummyP, dvm, disc,
                                               sysa, xc, xp, xtab, f1, s_new, P_new, KS, KP, KT,
                                               ytmp, Ptmp, fel, err_w, ft, SR, row_tn)
                        else:
                            st = rk_step_free(meth, t_new, tau, s_try, dummyP, dvm, disc, sysa,
                                              xc, xp, xtab, f1, s_new, P_new, KS, KP, ytmp, Ptmp,
                                              fel, err_w)
                        t_new = t_new + tau
                        st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1,
                                   KP[0], fel)
                    yv, ydv, yddv, st2 = excite(t_new, xc, xp, xtab)
                    d, dd = kinematics(pe, s_new, yv, ydv, sysa)
                    if d > 0.0 and dd < 0.0:
                        # land on the far side (delta <= 0) of the boundary
                        tau = -2.0 * d / dd
                        for q in range(n):
                            s_try[q] = s_new[q]
                            if want_var:
                                for c in range(m):
                                    dummyP[q, c] = P_new[q, c]
                        if want_var:
                            st = var_time_step(meth, t_new, tau, s_try, dummyP, dvm, disc,
                                               sysa, xc, xp, xtab, f1, s_new, P_new, KS, KP, KT,
                                               ytmp, Ptmp, fel, err_w, ft, SR, row_tn)
                        else:
                            st = rk_step_free(meth, t_new, tau, s_try, dummyP, dvm, disc, sysa,
                                              xc, xp, xtab, f1, s_new, P_new, KS, KP, ytmp, Ptmp,
                                              fel, err_w)
                        t_new = t_new + tau
                        st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1,
                                   KP[0], fel)
                    if want_var:
                        # the landing time is the boundary's: its derivative (the last polishing
                        # steps are short: the step's derivative in its length is the field)
                        boundary_time_sens(pe, t_new, f1, P_new, SR, SR[SR_DSC], 0.0, sysa, xc, xp,
                                           xtab)
                    ev = pe
                    tau_ev = t_new - t
                    phase = 0
            else:
                # ---- an ordinary step in time
                if fixed:
                    tg = t0 + (k_grid + 1) * dt if k_grid + 1 < n_grid else t_end
                    if n_in > 0:
                        hc = np.inf
                        e_h = -1
                        for e in range(ne):
                            if disc[e, 0] != 0.0 and dtc[e] < hc:
                                hc = dtc[e]
                                e_h = e
                        # explicit stability: the law's stiffness and damping rates
                        lam = contact_rate(t, s, disc, sysa, xc, xp, xtab)
                        capped = False
                        if lam * hc > 0.5:
                            hc = 0.5 / lam
                            capped = True
                        h = hc
                        if h >= t_end - t:
                            h = t_end - t
                            hit_grid = True
                        if want_var:
                            # the step's sensitivity: the contact step's, the stability limit's
                            # (through the state), or -dt/dz when the step ends at t_end
                            if hit_grid:
                                for c in range(m):
                                    SR[SR_H, c] = -SR[SR_T, c]
                            elif capped:
                                contact_rate_sens(t, s, P, dvm, disc, SR[SR_T], sysa, xc, xp, xtab,
                                                  SR[SR_H])
                                for c in range(m):
                                    SR[SR_H, c] *= -0.5 / (lam * lam)
                            else:
                                for c in range(m):
                                    SR[SR_H, c] = SE[SE_DTC, e_h, c]
                    else:
                        h = tg - t
                        hit_grid = True
                        if want_var and t_dep:
                            for c in range(m):
                                SR[SR_H, c] = -SR[SR_T, c]   # onto the grid: t fixed at the end
                elif want_var and t_dep:
                    # the controller's steps taken as given, the last one ending at t_end
                    hh = -1.0 if h >= t_end - t else 0.0
                    for c in range(m):
                        SR[SR_H, c] = hh * SR[SR_T, c]
                if not fixed:
                    if h >= t_end - t:
                        h = t_end - t
                    if h < 1e-14 * max(abs(t), 1.0):
                        status = ERR_STEP_UNDERFLOW
                        break
                # with the variational equations: a step whose start or length depends on the state
                # (after an event, inside a contact) carries those sensitivities (rk_step_sens); in
                # free flight from a grid point neither does, and the plain variational step serves
                moving = want_var and (t_dep or n_in > 0 and fixed)
                sens_step = moving
                if not want_var:
                    # without them: straight to the unrolled RK4/DP5 step (what rk_step would
                    # call), one call level less per step; RK2 by its tableau
                    if meth != RK2:
                        st = _rk_step_plain(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0,
                                            s_new, KS, KP, ytmp, fel, err_w)
                    else:
                        st = rk_step_free(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0,
                                          s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
                elif moving:
                    # mode = phase (0 here) and e = pe, as at the graded steps' calls: the three
                    # calls share one compiled rk_step_sens (with literal modes numba compiled
                    # one per call, and every step of this loop, free flight too, cost ~20 %
                    # more)
                    st, t_dum = rk_step_sens(meth, phase, 0.0, h, 0.0, pe, s, t, P, dvm, disc,
                                             sysa, xc, xp, xtab, s_new, P_new, KS, KP, KT, ytmp,
                                             Ptmp, fel, ft, err_w, SR, row_t)
                elif not _HAS_USER and meth == RK4:
                    # the unrolled RK4 step with the variational equations, likewise
                    st = _rk_step_var(t, h, s, P, dvm, disc, sysa, xc, xp, xtab, s_new, P_new, KS,
                                      KP, ytmp, Ptmp, fel)
                else:
                    st = rk_step_with_var(meth, t, h, s, P, dvm, disc, sysa, xc, xp, xtab, f0,
                                          s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
                n_rhs += ns - (0 if want_var else 1)
                if st != 0:
                    status = st
                    break
                if not fixed:
                    en = 0.0
                    for q in range(n):
                        sc = atol + rtol * max(abs(s[q]), abs(s_new[q]))
                        en += (err_w[q] / sc) ** 2
                    en = math.sqrt(en / n)
                    if en > 1.0:
                        h = h * max(0.2, 0.9 * en ** -0.2)
                        n_rej += 1
                        n_steps += 1
                        continue
                if fixed:
                    if hit_grid:
                        t_new = t_end if n_in > 0 else tg
                    else:
                        t_new = t + h
                else:
                    t_new = t_end if t + h >= t_end else t + h
                if not fixed and t_new == t + h:
                    # first same as last: DP5's stage 7 is f(t + h, s_new), bit for bit
                    for q in range(n):
                        f1[q] = KS[6, q]
                    st = 0
                else:
                    # f at the step end (the next step's stage 1), inlined: the same values as deriv
                    st = deriv_plain(t_new, s_new, P_new, dvm, disc, sysa, xc, xp, xtab, f1, KP[0],
                                     fel)
                    n_rhs += 1
                if st != 0:
                    status = st
                    break
                if events_on:
                    for e in range(ne):
                        if not has_event(etype[e]):
                            continue
                        if not _may_cross(e, t, t_new - t, s, s_new, disc, sysa, xc, xp, xtab):
                            continue
                        tau, st = _crossing(meth, t, t_new - t, s, s_new, f0, f1, P, dvm, disc, e,
                                            sysa, xc, xp, xtab, s_try, dummyP, KS, KP, ytmp, Ptmp,
                                            fel, err_w)
                        if st != 0:
                            status = st
                            break
                        if tau >= 0.0 and (ev < 0 or tau < tau_ev):
                            tau_ev = tau
                            ev = e
                    if status != 0:
                        break
                    # the start of the graded exit phase: delta falls through d_sw
                    if fixed and graded and n_in == 1 and phase == 0:
                        if d_sw[pe] > 0.0:
                            y0, yd0, ydd0, st2 = excite(t, xc, xp, xtab)
                            y1, yd1, ydd1, st2 = excite(t_new, xc, xp, xtab)
                            d0, dd0 = kinematics(pe, s, y0, yd0, sysa)
                            d1, dd1 = kinematics(pe, s_new, y1, yd1, sysa)
                            if d0 > d_sw[pe] and d1 <= d_sw[pe] and dd0 < 0.0:
                                tau, st = locate(meth, t, 0.0, t_new - t, d_sw[pe] - d0,
                                                 d_sw[pe] - d1, s, P, dvm, disc, pe, -1.0, d_sw[pe],
                                                 sysa, xc, xp, xtab, f0, s_try, dummyP, KS, KP,
                                                 ytmp, Ptmp, fel, err_w)
                                if st != 0:
                                    status = st
                                    break
                                if ev < 0 or tau < tau_ev:
                                    ev = np.int64(-1)
                                    tau_ev = tau
                                    enter_exit = True
                if ev >= 0 or enter_exit:
                    # re-take the step up to the boundary
                    if want_var:
                        for c in range(m):
                            SR[SR_H, c] = 0.0
                    if want_var and not t_dep:
                        for c in range(m):
                            SR[SR_T, c] = 0.0
                    if want_var:
                        st = var_time_step(meth, t, tau_ev, s, P, dvm, disc, sysa, xc, xp, xtab,
                                           f0, s_new, P_new, KS, KP, KT, ytmp, Ptmp, fel,
                                           err_w, ft, SR, row_t)
                    else:
                        st = rk_step_free(meth, t, tau_ev, s, P, dvm, disc, sysa, xc, xp, xtab,
                                          f0, s_new, P_new, KS, KP, ytmp, Ptmp, fel, err_w)
                    sens_step = True
                    if st != 0:
                        status = st
                        break
                    if want_var:
                        # its length is the boundary's time, a function of the state
                        st = step_length_derivative(meth, t, tau_ev, s, disc, sysa, xc, xp, xtab,
                                                    s_try, KS, KT, ytmp, fel, ft, err_w, W1, KP1,
                                                    SR1, Bv)
                        if ev >= 0:
                            boundary_time_sens(ev, t + tau_ev, Bv, P_new, SR, SR[SR_DSC], 0.0, sysa,
                                               xc, xp, xtab)
                        else:
                            boundary_time_sens(pe, t + tau_ev, Bv, P_new, SR, SE[SE_DSW, pe], 1.0,
                                               sysa, xc, xp, xtab)
                    t_new = t + tau_ev
                    hit_grid = False
                    st = deriv(t_new, s_new, P_new, dvm, disc, False, sysa, xc, xp, xtab, f1, KP[0],
                               fel)
                    n_rhs += 1
            # ---- accept the step (t, s) -> (t_new, s_new)
            n_steps += 1
            for e in range(ne):
                if disc[e, 0] != 0.0:
                    steps_in_contact[e] += 1
            if track_xmax:
                track_xmax_step(s, f0, s_new, f1, t_new - t, N, xmax)
            if fixed and graded and n_in == 1 and disc[pe, 0] != 0.0 and t_new > t:
                # the maximum penetration of this contact sets where the graded exit phase starts
                y0, yd0, ydd0, st2 = excite(t, xc, xp, xtab)
                y1, yd1, ydd1, st2 = excite(t_new, xc, xp, xtab)
                d0, dd0 = kinematics(pe, s, y0, yd0, sysa)
                d1, dd1 = kinematics(pe, s_new, y1, yd1, sysa)
                if dd0 > 0.0 and dd1 <= 0.0:
                    th, dm = delta_extremum(pe, 1.0, t, t_new - t, s, s_new, f0, f1, sysa, xc, xp,
                                            xtab)
                    d_sw[pe] = KAPPA * max(dm, d0, d1)
                    if want_var:
                        dsw_sens(pe, KAPPA, t, t_new, th, dm, d0, d1, yd0, yd1, s, s_new, f0, f1, P,
                                 P_new, dvm, disc, SR, sysa, xc, xp, xtab, KS, KP, fel, ft,
                                 SE[SE_DSW, pe])
            # grid samples passed by this step: exact at a grid hit, dense output otherwise
            k_grid, n_stored = grid_samples(k_grid, n_grid, n_stored, store_every, t0, dt, t_end, t,
                                            t_new, hit_grid, s, f0, s_new, f1, ytmp, disc, xc, xp,
                                            xtab, sysa, out_t, out_s, out_d, out_f)
            t = t_new
            for q in range(n):
                s[q] = s_new[q]
                f0[q] = f1[q]
            if want_var:
                for q in range(n):
                    for c in range(m):
                        P[q, c] = P_new[q, c]
                if sens_step:
                    for c in range(m):
                        SR[SR_T, c] = SR[SR_TN, c]
                    # a step onto the grid point: the time no longer depends on the state
                    t_dep = not (fixed and hit_grid and n_in == 0)
            if enter_exit:
                phase = 2
                g_u = math.sqrt(d_sw[pe])
                # n_grade * grade_multiple steps in u (the first, the longest, about
                # 2 dtn / (3 m) <= dt), their number a function of dt and the contact step only
                g_n = n_grade * grade_multiple(dtn[pe], dt)
                g_h = g_u / g_n
                if want_var:
                    for c in range(m):
                        SR[SR_U0, c] = SE[SE_DSW, pe, c] / (2.0 * g_u)
                        SR[SR_GH, c] = SR[SR_U0, c] / g_n
            # ---- switch the discrete state at an event
            if ev >= 0:
                y, yd, ydd, st = excite(t, xc, xp, xtab)
                d, dd = kinematics(ev, s, y, yd, sysa)
                if n_events < ev_log.shape[0]:
                    ev_log[n_events, 0] = t
                    ev_log[n_events, 1] = ev
                    ev_log[n_events, 2] = 1.0 if disc[ev, 0] == 0.0 else 0.0
                    ev_log[n_events, 3] = dd
                n_events += 1
                if abs(d) > max_land:
                    max_land = abs(d)
                if disc[ev, 0] == 0.0:
                    vm = dd if dd > VMINUS_FLOOR else VMINUS_FLOOR
                    dd2 = sysa.ewy[ev] * ydd
                    for j in range(N):
                        dd2 += sysa.ew[ev, j] * f0[N + j]
                    dtn[ev] = contact_step(ev, vm, dd2, sysa, spc)
                    dtc[ev] = dtn[ev]
                    if fixed and dtc[ev] > dt:
                        dtc[ev] = dt  # a soft contact never gets a longer step than free flight
                    if want_var:
                        # the onset velocity and the contact steps as functions of the state (the
                        # landed sensitivities P, SR[SR_T]; the free-flight field: before the
                        # switch)
                        onset_sens(ev, t, s, P, dvm, disc, dd, ydd, dd2, dtc[ev] < dtn[ev], SR, SE,
                                   sysa, xc, xp, xtab, KS, KP, fel, ft, spc)
                    disc[ev, 0] = 1.0
                    disc[ev, 1] = vm
                    n_imp += 1
                    steps_in_contact[ev] = 0
                    d_sw[ev] = -1.0
                    if fixed and graded and dd > 0.0 and n_in == 0:
                        phase = 1
                        pe = ev
                        g_t0 = t
                        g_u = 0.0
                        # the phase spans n_grade nominal contact steps (a quarter of the
                        # contact, whatever dt is) in g_n uniform steps of sigma; the last
                        # lasts g_end^2 (2 g_n - 1) / g_n^2 < 2 dtn / grade_multiple <= dt
                        g_end = math.sqrt(n_grade * dtn[ev])
                        g_n = n_grade * grade_multiple(dtn[ev], dt)
                        g_h = g_end / g_n
                        if want_var:
                            for c in range(m):
                                SR[SR_TREF, c] = SR[SR_T, c]
                                SR[SR_U0, c] = 0.0
                                SR[SR_GEND, c] = n_grade * SE[SE_DTN, ev, c] / (2.0 * g_end)
                                SR[SR_GH, c] = SR[SR_GEND, c] / g_n
                    else:
                        phase = 0
                else:
                    disc[ev, 0] = 0.0
                    if from_before[ev]:
                        from_before[ev] = False
                    else:
                        n_contacts += 1
                        if steps_in_contact[ev] < min_spc:
                            min_spc = steps_in_contact[ev]
                    dtc[ev] = np.inf
                    d_sw[ev] = -1.0
                    phase = 0
                # f0 after the switch (the field is continuous; the law's memory changed)
                st = deriv(t, s, P, dvm, disc, False, sysa, xc, xp, xtab, f0, KP[0], fel)
                n_rhs += 1
            if k_grid >= n_grid:
                t = t_end
            if not fixed:
                if en == 0.0:
                    fac = 5.0
                else:
                    fac = min(5.0, max(0.2, 0.9 * en ** -0.2))
                h = h * fac
                if ev >= 0:
                    h = min(h, max(1e-3 * dt, 1e-9))

        for q in range(n):
            s_end[q] = s[q]
            for c in range(m):
                P_end[q, c] = P[q, c]
        for e in range(ne):
            disc_end[e, 0] = disc[e, 0]
            disc_end[e, 1] = disc[e, 1]
            for c in range(m):
                dvm_end[e, c] = dvm[e, c]
        counters[0] = n_stored
        counters[1] = n_steps
        counters[2] = n_rej
        counters[3] = n_rhs
        counters[4] = n_imp
        counters[5] = min_spc if n_contacts > 0 else -1
        counters[6] = n_contacts
        counters[7] = n_events
        if counters.shape[0] > 8:
            counters[8] = n_routine
        fcounters[0] = t
        fcounters[1] = max_land
        return status

    return _integrate_loop


_loop_plain = _loop_for(False)
_loop_var = _loop_for(True)
