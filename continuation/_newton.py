"""Newton's method on a square system, and the error it raises when it does not converge."""
from __future__ import annotations

import numpy as np

from nlbeam import _linalg as la


class ConvergenceError(RuntimeError):
    """A Newton iteration did not converge; the message says what to try."""


class ContinuationWarning(UserWarning):
    """A result to look at: a branch stopped early (no progress), or a periodic solution of
    lower order than asked; the message says where and what to change."""


HINT = ("try: a guess from a nearby solution (guess=...), multiple shooting (segments=4 or more, "
        "for unstable or strongly contracting orbits), a smaller continuation step, or finer "
        "integration (dt_scale=0.5)")


def newton(fun, z0, *, tol=1e-10, max_iter=12, what="Newton", residual=None):
    """Solve fun(z) = 0 from z0. ``fun(z) -> (residual, jacobian)``, both already scaled so that
    the residual's max-norm is what ``tol`` bounds. With ``residual(z) -> residual`` the
    Jacobian is taken once, at z0, and then updated by Broyden's rank-one formula (a
    quasi-Newton iteration for when the Jacobian is costly). Returns (z, residual_norm,
    iterations); raises ConvergenceError (message with hints) when max_iter is reached or a
    step fails."""
    z = np.array(z0, dtype=float)
    r, J = fun(z)
    res = float(np.max(np.abs(r)))
    for it in range(1, max_iter + 1):
        if not np.isfinite(res):
            break
        try:
            dz = la.solve(J, -r)
        except np.linalg.LinAlgError:
            raise ConvergenceError(f"{what}: singular Jacobian at iteration {it}; {HINT}") from None
        z = z + dz
        if residual is None:
            r, J = fun(z)
        else:
            r_old, r = r, residual(z)
            J = J + np.outer(r - r_old - la.matmul(J, dz), dz) / la.dot(dz, dz)
        res_new = float(np.max(np.abs(r)))
        step = float(np.max(np.abs(dz)))
        if res_new <= tol or (step <= 1e-3 * tol and res_new <= 1e3 * tol):
            return z, res_new, it
        if res_new > 1e8 * max(res, tol) or not np.isfinite(res_new):
            res = res_new
            break
        res = res_new
    raise ConvergenceError(f"{what}: no convergence after {max_iter} iterations (scaled residual "
                           f"{res:.2e} > tol {tol:.1e}); {HINT}")
