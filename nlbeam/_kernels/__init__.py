"""Compiled kernels: excitation, element forces, right-hand side, event-exact Runge-Kutta.

Private. Every function here takes arrays, writes into preallocated outputs and returns an
integer status; none validates input, draws random numbers or raises. The Python layer
(``nlbeam.integrate``) checks arguments and turns status codes into messages.

Files by job (imports run down this list): ``force``/``hook`` (compile settings, custom-force
hook), ``bundles`` (named arguments), ``codes`` (element, method and status codes, tableaus),
``excite`` (excitation), ``field`` (element forces, right-hand sides), ``contact`` (contact
step and rate), ``steps`` (RK steps), ``graded`` (graded contact steps), ``events`` (dense
output, extrema, boundary location), ``loop`` (``integrate_kernel``).

Arguments come in named bundles (``bundles``): the system arrays ``sysa`` (a SystemArrays
built by ``nlbeam.System.kernel_arrays``), the excitation (code, p, tab), and for
``integrate_kernel`` the Settings, Start and Outputs.
Element e: delta_e = ew_e . x + ewy_e * y - egap_e, generalised force -ew_e f_e.
Discrete state ``disc`` (ne, 2): [in_contact (0/1), delta'_minus].
"""
from .stale_cache import check_package as _check_cache

_check_cache()  # before any kernel loads: caches built from other sources are dropped

from .bundles import Outputs, Settings, Start, SystemArrays, Work, outputs, settings, start
from .codes import (_A_DP5, _A_RK2, _A_RK4, _B_DP5, _B_RK2, _B_RK4, _BH_DP5, _C_DP5,
                    _C_RK2, _C_RK4, CUBIC, DP5, ERR_EVENT, ERR_EXCITATION_RANGE, ERR_MAX_STEPS,
                    ERR_NONFINITE, ERR_STEP_UNDERFLOW, HERTZ, HUNT_CROSSLEY, INACTIVE, LANKARANI,
                    OK, PWL_STOP, RK2, RK4, VMINUS_FLOOR)
from .contact import contact_rate, contact_step
from .events import delta_after, delta_extremum, hermite5, locate, step_extrema
from .excite import excitation_many, excite, excite_yyd
from .field import deriv, deriv_plain, deriv_var, element_force, has_event, kinematics
from .graded import rk_step_graded
from .loop import integrate_kernel, integrate_plain, integrate_var
from .steps import rk_step, tableau

__all__ = [
    "Outputs", "Settings", "Start", "SystemArrays", "Work", "outputs", "settings", "start",
    "_A_DP5", "_A_RK2", "_A_RK4", "_B_DP5", "_B_RK2", "_B_RK4", "_BH_DP5", "_C_DP5", "_C_RK2",
    "_C_RK4", "CUBIC", "DP5", "ERR_EVENT", "ERR_EXCITATION_RANGE", "ERR_MAX_STEPS",
    "ERR_NONFINITE", "ERR_STEP_UNDERFLOW", "HERTZ", "HUNT_CROSSLEY", "INACTIVE", "LANKARANI", "OK",
    "PWL_STOP", "RK2", "RK4", "VMINUS_FLOOR", "contact_rate", "contact_step", "delta_after",
    "delta_extremum", "hermite5", "locate", "step_extrema", "excitation_many", "excite",
    "excite_yyd", "deriv", "deriv_plain", "deriv_var", "element_force", "has_event", "kinematics",
    "rk_step_graded", "integrate_kernel", "integrate_plain", "integrate_var", "rk_step",
    "tableau",
]
