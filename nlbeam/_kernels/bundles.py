"""Named bundles of the kernels' arguments (numba-typed namedtuples), N DOFs, ne elements,
m sensitivity columns.

``integrate_kernel`` takes the system, settings, start and outputs as *plain* tuples in the
field order below, built by the functions of this module, and names them inside the compiled
code (``SystemArrays(*system)``: free). Numba's dispatcher types a namedtuple argument field by
field through its name (about 60 ns a field): namedtuples at the call cost 4.6 us more a call
than the former 34 positional arguments, plain tuples 0.3 us (one FlowMap call: ~14 us).
"""
from collections import namedtuple

SystemArrays = namedtuple("SystemArrays", [
    "MinvK",   # (N, N) M^-1 K
    "MinvC",   # (N, N) M^-1 C
    "mek",     # (N,) M^-1 (load of y)
    "mec",     # (N,) M^-1 (load of y')
    "etype",   # (ne,) int64 element codes (codes.py)
    "ew",      # (ne, N) w_e: delta_e = w_e . x + wy_e y - gap_e
    "ewy",     # (ne,) wy_e
    "egap",    # (ne,) gap_e (m)
    "epar",    # (ne, 4) law parameters
    "mw",      # (ne, N) M^-1 w_e
    "upar",    # (>= 1,) parameters of the custom force
    "uf",      # (4, N) work rows of the custom force (its values and perturbed states)
    "Minv",    # (N, N) M^-1
])
SystemArrays.__doc__ = """The system as the kernels see it (``nlbeam.System.kernel_arrays``):
a = mek y + mec y' - MinvC v - MinvK x - sum_e mw_e f_e (+ M^-1 of the custom force)."""

Settings = namedtuple("Settings", [
    "meth",         # int: codes.RK2, RK4 or DP5
    "t0",           # float: start time (s)
    "t_end",        # float: end time (s)
    "dt",           # float: grid step (s): fixed step in free flight, DP5's output spacing
    "spc",          # float: steps per contact
    "rtol",         # float: DP5's relative tolerance
    "atol",         # float: DP5's absolute tolerance
    "h_init",       # float: DP5's first step (s)
    "max_steps",    # int: steps (accepted and rejected) before ERR_MAX_STEPS
    "events_on",    # bool: locate contact boundaries
    "want_var",     # bool: integrate the variational equations
    "track_xmax",   # bool: max |x_i| over the run into Outputs.xmax
    "store_every",  # int: keep every k-th grid sample (0: none)
    "graded",       # bool: graded steps at the ends of a contact
    "routine",      # bool: routine RK4 steps in the lean loop (routine.py; the same results)
])

Start = namedtuple("Start", [
    "s0",     # (2N,) state at t0
    "disc0",  # (ne, 2) discrete state at t0 [in contact, delta'_minus]
    "P0",     # (2N, m) sensitivities at t0
    "dvm0",   # (ne, m) sensitivities of delta'_minus at t0
])

Outputs = namedtuple("Outputs", [
    "t",          # (n_samples,) sample times (s)
    "s",          # (n_samples, 2N) states at the samples
    "delta",      # (n_samples, ne) penetrations (m)
    "force",      # (n_samples, ne) element forces (N)
    "ev_log",     # (cap, 4) [t, element, 1 onset / 0 end, delta'] of the first cap events
    "s_end",      # (2N,) state at the end
    "disc_end",   # (ne, 2) discrete state at the end
    "P_end",      # (2N, m) sensitivities at the end
    "dvm_end",    # (ne, m) sensitivities of delta'_minus at the end
    "xmax",       # (N,) max |x_i| over the run (updated in place)
    "counters",   # (8,) or (9,) int64 [n_stored, n_steps, n_rejected, n_rhs, n_impacts,
                  #   min_steps_per_contact, n_contacts, n_events(, steps by routine.py)]
    "fcounters",  # (2,) [t reached, max |delta| at a landed event]
])

Work = namedtuple("Work", [
    "KS", "KP", "KT",        # (ns, 2N), (ns, 2N, m), (ns,) stage slopes (state, P, time)
    "ytmp", "Ptmp",          # (2N,), (2N, m) stage state
    "fel", "err_w",          # (ne,) element forces, (2N,) DP5's error estimate
    "s", "P", "dvm", "disc",  # the current state, sensitivities and discrete state
    "s_new", "P_new",        # the step's end
    "s_try", "dummyP",       # trial steps of the event location
    "f0", "f1",              # f at the step's start and end
    "steps_in_contact",      # (ne,) int64 steps of the current contact
    "from_before",           # (ne,) bool: contact under way at t0
    "dtc",                   # (ne,) step inside the current contact (s; inf: none)
    "d_sw",                  # (ne,) delta where the graded exit phase starts (-1: unknown)
    "dtn",                   # (ne,) nominal contact step: contact duration / spc (s)
    # the derivative of the map as computed (sens_steps.py), with want_var:
    "SR", "SE",              # (SR_ROWS, m), (SE_ROWS, ne, m) sensitivities of times and steps
    "ft",                    # (2N,) df/dt at a fixed state
    "W1", "KP1", "SR1",      # (4, max(2N, ne), 1), (ns, 2N, 1), (SR_ROWS, 1): one column
    "Bv",                    # (2N,) a step's derivative in its length
])
Work.__doc__ = "Work arrays of the integration loop, allocated by ``integrate_kernel``."


def settings(*, meth, t0, t_end, dt, spc, rtol, atol, h_init, max_steps, events_on, want_var,
             track_xmax, store_every, graded, routine=True):
    """The Settings fields as integrate_kernel takes them: a plain tuple, each value of the type
    the kernel is compiled for (an int where a float is due would compile a second version)."""
    return (int(meth), float(t0), float(t_end), float(dt), float(spc), float(rtol), float(atol),
            float(h_init), int(max_steps), bool(events_on), bool(want_var), bool(track_xmax),
            int(store_every), bool(graded), bool(routine))


def start(*, s0, disc0, P0, dvm0):
    """The Start fields as a plain tuple (arrays of float64)."""
    return (s0, disc0, P0, dvm0)


def outputs(*, t, s, delta, force, ev_log, s_end, disc_end, P_end, dvm_end, xmax, counters,
            fcounters):
    """The Outputs fields as a plain tuple (arrays the kernel writes into)."""
    return (t, s, delta, force, ev_log, s_end, disc_end, P_end, dvm_end, xmax, counters,
            fcounters)
