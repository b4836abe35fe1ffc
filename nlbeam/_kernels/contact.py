"""Time scales of a contact: the step inside a contact (estimated duration / steps per contact)
and the largest rate of the contact laws (the explicit stability limit)."""
import math

from .codes import _T_C_HERTZ, PWL_STOP
from .excite import excite
from .field import element_force, kinematics
from .hook import njit


@njit(cache=True)
def contact_step(e, v0, a0, sysa, spc):
    """Time step inside a contact of element e that starts at penetration rate v0 (m/s) and
    free-flight penetration acceleration a0 (m/s^2): the estimated contact duration divided by
    spc. The duration is that of a free mass on the stop, or of a grazing touch, 2 v0 / |a0|,
    when a0 < 0 makes that shorter."""
    etype = sysa.etype
    ew = sysa.ew
    epar = sysa.epar
    mw = sysa.mw
    winv = 0.0
    for j in range(ew.shape[1]):
        winv += ew[e, j] * mw[e, j]
    meff = 1.0 / winv
    K = epar[e, 0]
    if etype[e] == PWL_STOP:
        tc = math.pi * math.sqrt(meff / K)
    else:
        v = max(v0, 1e-12)
        dmax = (1.25 * meff * v * v / K) ** 0.4
        tc = _T_C_HERTZ * dmax / v
    if a0 < 0.0:
        tg = 2.0 * max(v0, 1e-12) / (-a0)
        if tg < tc:
            tc = tg
    return tc / spc

@njit(cache=True)
def contact_rate(t, s, disc, sysa, xc, xp, xtab):
    """Largest rate (1/s) of the contact laws at (t, s): sqrt(stiffness / m_eff) and
    damping / m_eff of every element in contact; explicit steps need rate * h < 0.5."""
    etype = sysa.etype
    N = s.shape[0] // 2
    y, yd, ydd, st = excite(t, xc, xp, xtab)
    lam = 0.0
    for e in range(etype.shape[0]):
        if disc[e, 0] != 0.0:
            d, dd = kinematics(e, s, y, yd, sysa)
            f, dfd, dfdd, dfdv = element_force(etype[e], sysa.epar[e], d, dd, disc[e, 1],
                                               disc[e, 0])
            winv = 0.0
            for j in range(N):
                winv += sysa.ew[e, j] * sysa.mw[e, j]
            lam = max(lam, math.sqrt(max(dfd, 0.0) * winv), abs(dfdd) * winv)
    return lam
