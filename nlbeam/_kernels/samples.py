"""What the integration loop records after an accepted step: the grid samples the step passed
(exact at a grid hit, quintic dense output otherwise) and the running max |x_i|. Inlined into
both loops (loop.py, routine.py), so both record the same doubles."""
from .events import hermite5, step_extrema
from .excite import excite_yyd
from .field import element_force
from .hook import njit


@njit(cache=True, inline="always")
def _store(n_stored, t, s, disc, xc, xp, xtab, sysa, out_t, out_s, out_d, out_f):
    """Write sample n_stored: t, s, and delta and force of every element. Inlined into the
    integrator's loop, with y'' skipped and the penetration computed in place (the same
    expressions as ``kinematics``): a call with the system's arrays cost ~100 ns a sample."""
    y, yd, st = excite_yyd(t, xc, xp, xtab)
    etype = sysa.etype
    ew = sysa.ew
    N = ew.shape[1]
    out_t[n_stored] = t
    for q in range(s.shape[0]):
        out_s[n_stored, q] = s[q]
    for e in range(etype.shape[0]):
        d = sysa.ewy[e] * y - sysa.egap[e]
        dd = sysa.ewy[e] * yd
        for j in range(N):
            d += ew[e, j] * s[j]
            dd += ew[e, j] * s[N + j]
        out_d[n_stored, e] = d
        f, a1, a2, a3 = element_force(etype[e], sysa.epar[e], d, dd, disc[e, 1], disc[e, 0])
        out_f[n_stored, e] = f
    return n_stored + 1


@njit(cache=True, inline="always")
def grid_samples(k_grid, n_grid, n_stored, store_every, t0, dt, t_end, t, t_new, hit_grid, s,
                 f0, s_new, f1, ytmp, disc, xc, xp, xtab, sysa, out_t, out_s, out_d, out_f):
    """Pass the grid points t0 + k dt up to the step's end t_new: store every store_every-th
    (exact at a grid hit, the quintic Hermite dense output otherwise; ytmp (2N,) work).
    Returns (k_grid, n_stored) after the step."""
    N = s.shape[0] // 2
    while k_grid < n_grid:
        kk = k_grid + 1
        tgk = t0 + kk * dt if kk < n_grid else t_end
        exact = hit_grid and (kk == n_grid or tgk >= t_new - 1e-15 * abs(t_new))
        if tgk > t_new and not exact:
            break
        k_grid = kk
        if store_every > 0 and (kk % store_every == 0 or kk == n_grid):
            if exact:
                n_stored = _store(n_stored, t_new, s_new, disc, xc, xp, xtab, sysa,
                                  out_t, out_s, out_d, out_f)
            else:
                th = (tgk - t) / (t_new - t)
                for i in range(N):
                    xk, vk = hermite5(s[i], s[N + i], f0[N + i], s_new[i], s_new[N + i],
                                      f1[N + i], t_new - t, th)
                    ytmp[i] = xk
                    ytmp[N + i] = vk
                n_stored = _store(n_stored, tgk, ytmp, disc, xc, xp, xtab, sysa,
                                  out_t, out_s, out_d, out_f)
        if exact:
            break
    return k_grid, n_stored


@njit(cache=True, inline="always")
def track_xmax_step(s, f0, s_new, f1, hh, N, xmax):
    """Raise xmax[i] to max |x_i| over the step (t, s) -> (t + hh, s_new). The refinement on
    the dense output only where a velocity changes sign and the quintic can exceed the
    current max: |x(theta)| <= max(|x0|, |x1|) + h (|v0| + |v1|) max|H1| + h^2 (|a0| + |a1|)
    max|H2| (H0 + H3 = 1, both in [0, 1]; max|H4| = max|H1| = 16/81, max|H5| = max|H2| =
    0.01728), so a skipped refinement could not have raised xmax: the same xmax bit for bit,
    without most of the bisections."""
    refine = False
    for i in range(N):
        a = abs(s_new[i])
        if a > xmax[i]:
            xmax[i] = a
        if s[N + i] * s_new[N + i] < 0.0:
            bnd = (max(abs(s[i]), a) + hh * 0.19754 * (abs(s[N + i]) + abs(s_new[N + i]))
                   + hh * hh * 0.017281 * (abs(f0[N + i]) + abs(f1[N + i])))
            if bnd * (1.0 + 1e-12) >= xmax[i]:
                refine = True
    if refine:
        step_extrema(s, f0, s_new, f1, hh, N, xmax)
