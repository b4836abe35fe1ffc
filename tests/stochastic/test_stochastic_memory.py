"""Memory stays flat in the record length (issue 15): the estimators stream, so a record 20
times longer needs no more memory than the chunks it is made of. Measured in a fresh process
(peak resident memory, /proc/self/status VmHWM) after a warm-up run, so that importing and
loading the kernels do not count; the same measurement with the record kept (keep_history)
shows that it sees memory that grows with the record."""
import json
import subprocess
import sys

import pytest

SCRIPT = r"""
import gc, json, sys
import nlbeam, stochastic as st

def peak_mib():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM"):
            return int(line.split()[1]) / 1024

model = nlbeam.BeamImpact.paper()
noise = st.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=1)
out = []
for duration, keep in json.loads(sys.argv[1]):
    r = st.simulate(model, noise, duration, transient=1.0, channels=("delta", "x"),
                    psd_resolution=0.5, keep_history=(0.0, duration) if keep else None)
    out.append([duration, peak_mib(), r.fs, r.n_impacts])
    del r
    gc.collect()
print(json.dumps(out))
"""


def _peaks(runs):
    res = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(runs)], capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/status")
def test_peak_memory_does_not_grow_with_the_record_length():
    """Paper beam, 0-100 Hz noise, rms 0.1 mm: after two 20 s warm-ups, a 25 s record and a
    1000 s one (with impacts all along) reach the same peak memory within half of what one
    channel of the longer record's extra 975 s would take as float64 samples (11.9 MiB);
    keeping the history of a 500 s record raises the peak by more than one channel of it.
    Measured (25 s against 500 s): +1 to +4 MiB; +70 MiB with the 500 s history kept."""
    _, (_, _, fs, _), (_, p25, _, _), (_, p1000, _, n1000), (_, p_kept, _, _) = _peaks(
        [[20.0, False], [20.0, False], [25.0, False], [1000.0, False], [500.0, True]])
    mib_per_s = fs * 8 / 2 ** 20  # one float64 channel: 0.024 MiB per s at fs = 3.2 kHz
    assert n1000 > 10000  # the long record is impacting throughout
    assert p1000 - p25 < 0.5 * 975.0 * mib_per_s, (p25, p1000, 975.0 * mib_per_s)
    # the measurement sees a record that is kept (x, delta and the times: >= 2 channels)
    assert p_kept - p1000 > 500.0 * mib_per_s, (p1000, p_kept, 500.0 * mib_per_s)
