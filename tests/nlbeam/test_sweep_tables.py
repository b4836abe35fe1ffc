"""Tables of a sweep carry the swept value (issue 14): every row of a peaks table names the
value of its variant, so the peaks of several excitation levels can be read from one file."""
import csv
from types import SimpleNamespace

import numpy as np

from nlbeam.app.scenes.outputs import write_table


def _variant(rms, f_peak, f):
    """A variant whose record's PSD has one resonance peak at f_peak (Hz) and whose diagram
    is a harmonic branch with its maximum there."""
    P = 1e-10 * (1 + 1e3 / (1 + ((f - f_peak) / 0.8) ** 2))
    sto = SimpleNamespace(psd=lambda ch: (f, P))
    fr = np.linspace(5.0, 150.0, 1451)
    per = SimpleNamespace(branches=[SimpleNamespace(
        order=1, frequency=fr, xmax=1e-4 + 1e-3 / (1 + ((fr - f_peak) / 2) ** 2),
        stable=np.ones(fr.size, bool))], bifurcations=[], superharmonics=[])
    p = {"f_range": [5.0, 150.0], "amplitude": 1e-4}
    s = {"band": [0.0, 200.0], "rms": rms, "seed": 1, "lowpass": None}
    label = f"rms={rms:g}"
    return (label, {}, p, s, per, sto, {"periodic": "frc", "stochastic": label})


def test_a_peaks_table_of_a_sweep_has_a_column_of_the_swept_value(tmp_path):
    f = np.arange(0.0, 200.0, 0.5)
    variants = [_variant(1e-4, 40.0, f), _variant(2e-4, 47.0, f)]
    values = {"rms=0.0001": 1e-4, "rms=0.0002": 2e-4}
    path = write_table({"kind": "peaks", "file": "peaks.csv", "f_max": 150.0}, variants,
                       str(tmp_path), swept=("rms", "m", values))
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:2] == ["variant", "rms"]
    got = sorted((float(r["rms"]), float(r["frequency_hz"])) for r in rows)
    # one peak per record, each at its own resonance, in the row of its own rms
    assert got == [(1e-4, 40.0), (2e-4, 47.0)]
    assert all(r["variant"] == f"rms={float(r['rms']):g}" for r in rows)
