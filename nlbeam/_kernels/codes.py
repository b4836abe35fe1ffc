"""Codes shared by the kernels and the Python layer: element types, methods, status codes, the
Butcher tableaus of RK2/RK4/DP5 and their nonzero entries as scalars for the unrolled steps."""
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

_A_RK4 = np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
_B_RK4 = np.array([1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0])
_C_RK4 = np.array([0.0, 0.5, 0.5, 1.0])

_A_DP5 = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0],
])
_B_DP5 = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0])
_BH_DP5 = np.array([5179.0 / 57600.0, 0.0, 7571.0 / 16695.0, 393.0 / 640.0, -92097.0 / 339200.0,
                    187.0 / 2100.0, 1.0 / 40.0])
_C_DP5 = np.array([0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0])

_T_C_HERTZ = 2.943275
VMINUS_FLOOR = 1e-6  # m/s: delta'_minus of a tangential (zero-rate) onset  # contact time of a free mass on a Hertz stop, in units d_max / v0


# the tableaus' nonzero entries as compile-time constants, for the unrolled steps below (the
# same Python expressions as the arrays above, so the same doubles)
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
_DC2, _DC3, _DC4, _DC5 = 0.2, 0.3, 0.8, 8.0 / 9.0
_R6, _R3 = 1.0 / 6.0, 1.0 / 3.0
