"""The scene ``nlbeam demo`` writes and runs (text of a scene file, see nlbeam.app.scenes)."""

import tomllib

__all__ = ["DEMO_SCENE", "demo_summary"]

#: the scene `nlbeam demo` runs: every kind of figure and table of `nlbeam figures`, on a
#: smaller diagram (30-100 Hz, orders 1 and 2) and 10 s records, broad band and the narrow
#: band around twice the harmonic resonance (the stochastic 1/2 subharmonic)
DEMO_SCENE = """\
# Written by `nlbeam demo`: a short version of `nlbeam figures` (the paper model).
# Re-run or edit it with: nlbeam run demo.toml --out DIR. Units: m, s, Hz.
title = "nlbeam demo: paper model, A = 0.1 mm / rms 0.1 mm"

[periodic]
amplitude = 1e-4            # m
f_range = [30.0, 100.0]     # Hz: the harmonic resonance (43.5) and the 1/2 subharmonic (87)
orders = [1, 2]
n_grid = 10

[stochastic]
band = [0.0, 200.0]         # Hz, replaced by the sweep values
rms = 1e-4                  # m
seed = 1
duration = 10.0             # s kept
transient = 1.0             # s discarded
psd_resolution = 0.5        # Hz
method = "rk4"              # fixed step, as before; stochastic.simulate's default: adaptive

[sweep]
parameter = "band"
values = [[0.0, 200.0], [78.0, 98.0]]

[[figure]]
kind = "frc"
file = "demo_frequency_response.png"
title = "|x|max vs excitation frequency, A = 0.1 mm, orders 1-2"

[[figure]]
kind = "excitation_psd"
file = "demo_excitation_psd.png"
f_max = 250.0

[[figure]]
kind = "pdf"
channel = "delta"
file = "demo_pdf_delta.png"

[[figure]]
kind = "history"
channels = ["y", "x"]
window = [0.0, 0.3]
file = "demo_time_history.png"

[[figure]]
kind = "psd"
channel = "delta"
f_max = 200.0
file = "demo_psd_delta.png"

[[figure]]
kind = "compare"
channel = "delta"
f_max = 200.0
file = "demo_compare.png"

[[table]]
kind = "moments"
channel = "delta"
file = "demo_moments.csv"

[[table]]
kind = "peaks"
channel = "delta"
f_max = 200.0
file = "demo_peaks.csv"

[[table]]
kind = "bifurcations"
file = "demo_bifurcations.csv"
"""


def demo_summary():
    """What the demo computes, read from DEMO_SCENE (the help text's one source)."""
    d = tomllib.loads(DEMO_SCENE)
    p, s = d["periodic"], d["stochastic"]
    bands = [f"{lo:g}-{hi:g} Hz" for lo, hi in d["sweep"]["values"]]
    return (f"the frequency-response diagram {p['f_range'][0]:g}-{p['f_range'][1]:g} Hz "
            f"(orders {', '.join(map(str, p['orders']))}), {s['duration']:g} s records under "
            f"base noise of rms {s['rms'] * 1e3:g} mm in the bands {' and '.join(bands)}")
