"""Codes shared by the kernels and the Python layer: element types, methods, status codes, the
Butcher tableaus of RK2/RK4/DP5, and the RK4/DP5 entries again as scalars for the unrolled steps
(steps.py, graded.py), checked against the tableaus on import (``check_unrolled``)."""
import numpy as np

# element types
INACTIVE = -1
HERTZ = 0
LANKARANI = 1
HUNT_CROSSLEY = 2
CUBIC = 3
PWL_STOP = 4

# methods
RK2 = 0
RK4 = 1
DP5 = 2

# status codes
OK = 0
ERR_EXCITATION_RANGE = 1
ERR_NONFINITE = 2
ERR_EVENT = 3
ERR_MAX_STEPS = 4
ERR_STEP_UNDERFLOW = 5

# --- Butcher tableaus: (A, b, b_hat, c) -----------------------------------------------------
_A_RK2 = np.array([[0.0, 0.0], [1.0, 0.0]])
_B_RK2 = np.array([0.5, 0.5])
_C_RK2 = np.array([0.0, 1.0])

_A_RK4 = np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.0],
                   [0.0, 0.0, 1.0, 0.0]])
_B_RK4 = np.array([1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0])
_C_RK4 = np.array([0.0, 0.5, 0.5, 1.0])

_A_DP5 = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0,
     0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0],
])
_B_DP5 = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
                   11.0 / 84.0, 0.0])
_BH_DP5 = np.array([5179.0 / 57600.0, 0.0, 7571.0 / 16695.0, 393.0 / 640.0, -92097.0 / 339200.0,
                    187.0 / 2100.0, 1.0 / 40.0])
_C_DP5 = np.array([0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0])

# contact time of a free mass on a Hertz stop, in units d_max / v0
_T_C_HERTZ = 2.943275
VMINUS_FLOOR = 1e-6  # m/s: delta'_minus of a tangential (zero-rate) onset


# --- the tableaus' entries as compile-time constants, for the unrolled steps -------------------
# (the same Python expressions as the arrays above, so the same doubles; check_unrolled below)
# RK4: a_ij, c_i (the zero a_31, a_41, a_42 and c_1 enter the graded step's time and stage 1),
# b = (1/6, 1/3, 1/3, 1/6)
_RA21 = 0.5
_RA31, _RA32 = 0.0, 0.5
_RA41, _RA42, _RA43 = 0.0, 0.0, 1.0
_RC1, _RC2, _RC3, _RC4 = 0.0, 0.5, 0.5, 1.0
_R6, _R3 = 1.0 / 6.0, 1.0 / 3.0
# DP5: a_ij, b_i (b_2 = b_7 = 0 dropped), e_i = b_i - b_hat_i, c_i
_D21 = 1.0 / 5.0
_D31, _D32 = 3.0 / 40.0, 9.0 / 40.0
_D41, _D42, _D43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_D51, _D52, _D53, _D54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_D61, _D62, _D63, _D64, _D65 = (9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0,
                                -5103.0 / 18656.0)
_DB1, _DB3, _DB4, _DB5, _DB6 = (35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
                                11.0 / 84.0)
_DE1 = _DB1 - 5179.0 / 57600.0
_DE3 = _DB3 - 7571.0 / 16695.0
_DE4 = _DB4 - 393.0 / 640.0
_DE5 = _DB5 - (-92097.0 / 339200.0)
_DE6 = _DB6 - 187.0 / 2100.0
_DE7 = 0.0 - 1.0 / 40.0
_DC2, _DC3, _DC4, _DC5, _DC6, _DC7 = 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0

TABLEAUS = {"A_RK4": _A_RK4, "b_RK4": _B_RK4, "c_RK4": _C_RK4, "A_DP5": _A_DP5,
            "b_DP5": _B_DP5, "e_DP5": _B_DP5 - _BH_DP5, "c_DP5": _C_DP5}


def unrolled_tableaus():
    """The RK4 and DP5 tableaus as the unrolled steps use them, built from the scalars above
    (0.0 where they drop a term); keys as in TABLEAUS. DP5's last row of A is b: its stage 7 is
    f at the step's end (first same as last)."""
    z = 0.0
    return {
        "A_RK4": [[z, z, z, z], [_RA21, z, z, z], [_RA31, _RA32, z, z], [_RA41, _RA42, _RA43, z]],
        "b_RK4": [_R6, _R3, _R3, _R6],
        "c_RK4": [_RC1, _RC2, _RC3, _RC4],
        "A_DP5": [[z, z, z, z, z, z, z],
                  [_D21, z, z, z, z, z, z],
                  [_D31, _D32, z, z, z, z, z],
                  [_D41, _D42, _D43, z, z, z, z],
                  [_D51, _D52, _D53, _D54, z, z, z],
                  [_D61, _D62, _D63, _D64, _D65, z, z],
                  [_DB1, z, _DB3, _DB4, _DB5, _DB6, z]],
        "b_DP5": [_DB1, z, _DB3, _DB4, _DB5, _DB6, z],
        "e_DP5": [_DE1, z, _DE3, _DE4, _DE5, _DE6, _DE7],
        "c_DP5": [z, _DC2, _DC3, _DC4, _DC5, _DC6, _DC7],
    }


def check_unrolled(tableaus=None):
    """Raise AssertionError, naming the entry, where a scalar of the unrolled RK4/DP5 steps
    differs (bit for bit) from the tableau arrays that rk_step's loops use. ``tableaus``:
    arrays to check against instead of TABLEAUS' (by key; for tests). Run on import."""
    ref = dict(TABLEAUS)
    ref.update(tableaus or {})
    got = unrolled_tableaus()
    for key, want in ref.items():
        want = np.asarray(want, dtype=float)
        have = np.asarray(got[key], dtype=float)
        if have.shape != want.shape:
            raise AssertionError(f"nlbeam._kernels.codes: the unrolled {key} has shape "
                                 f"{have.shape}, the tableau {want.shape}")
        diff = np.argwhere(have != want)
        if diff.size:
            i = tuple(int(k) for k in diff[0])
            raise AssertionError(
                f"nlbeam._kernels.codes: the unrolled steps' {key}{list(i)} = {float(have[i])!r} "
                f"but the tableau array has {float(want[i])!r}: edit the scalars (_RA../_D..) and "
                "the arrays of codes.py together")
    if _RC2 != _RC3:
        raise AssertionError("nlbeam._kernels.codes: RK4's c_2 and c_3 differ, but the unrolled "
                             "variational step evaluates the excitation once for stages 2 and 3")


check_unrolled()
