"""A stochastic result (``stochastic.StochasticResult``) as an HDF5 file.

Attributes: ``format`` (checked on reading), the run's scalars (channels, outputs, fs, dt,
t_start, transient, duration, method, seed, counters, success, message). Groups: ``model``
and ``excitation`` (attributes), ``channels/<ch>/<psd|pdf|moments>`` (arrays as datasets,
scalars as attributes), ``history`` (the kept samples, if any). None is stored as "none".
"""
from __future__ import annotations


import h5py
import numpy as np

from stochastic.simulate import StochasticResult
from stochastic.simulate import _attr  # the same plain values as the result holds

from .stamped_hdf5 import read_result, write_result

__all__ = ["save_stochastic_result", "load_stochastic_result"]

FORMAT = "nlbeam.stochastic.result"  # and version: see stamped_hdf5.FORMATS


def save_stochastic_result(res, path):
    """Write ``res`` (a stochastic.StochasticResult) to HDF5 at ``path``: built in memory,
    stamped with format and checksums, then written atomically (temporary file in the same
    directory, then renamed; the usual file mode under the umask). A failure leaves nothing
    and raises one OSError line. Returns path."""
    with write_result(path, FORMAT) as tmp:  # in memory; stamped; then to disk atomically
        with h5py.File(tmp, "w") as f:
            meta = {"channels": ",".join(res.channels),
                    "outputs": ",".join(res.outputs), "fs": res.fs, "dt": res.dt,
                    "t_start": res.t_start, "transient": res.transient,
                    "duration": res.duration, "method": res.method, "seed": res.seed,
                    "nlbeam_version": res.nlbeam_version, "n_impacts": res.n_impacts,
                    "n_impacts_transient": res.n_impacts_transient,
                    "contact_fraction": np.asarray(res.contact_fraction, dtype=float),
                    "n_steps": res.n_steps, "n_chunks": res.n_chunks,
                    "n_samples": res.n_samples, "wall_time": res.wall_time,
                    "min_steps_per_contact": res.min_steps_per_contact,
                    "success": res.success, "message": res.message}
            for k, v in meta.items():
                f.attrs[k] = v if isinstance(v, np.ndarray) else _attr(v)
            g = f.create_group("model")
            for k, v in res.model_parameters.items():
                g.attrs[k] = _attr(v)
            g = f.create_group("excitation")
            for k, v in res.excitation_description.items():
                g.attrs[k] = _attr(v)
            for store, name in ((res.psd_data, "psd"), (res.pdf_data, "pdf"),
                                (res.moment_data, "moments")):
                for ch, data in store.items():
                    g = f.require_group(f"channels/{ch}/{name}")
                    for k, v in data.items():
                        if isinstance(v, np.ndarray):
                            g.create_dataset(k, data=v)
                        else:
                            g.attrs[k] = _attr(v)
            if res.history is not None:
                g = f.create_group("history")
                for k, v in res.history.items():
                    g.create_dataset(k, data=v)
    return path


def load_stochastic_result(path) -> StochasticResult:
    """Read a stochastic.StochasticResult written by ``save_stochastic_result``, after
    checking format and checksums (``stamped_hdf5.read_result``: ResultFileError says what
    is wrong in one line)."""
    def val(v):
        if isinstance(v, bytes):
            v = v.decode()
        if isinstance(v, np.generic):
            v = v.item()
        return v

    with read_result(path, FORMAT) as f:
        a = {k: val(v) for k, v in f.attrs.items()}
        stores = {"psd": {}, "pdf": {}, "moments": {}}
        chans = tuple(c for c in a["channels"].split(",") if c)
        for ch in chans:
            for name in stores:
                key = f"channels/{ch}/{name}"
                if key in f:
                    g = f[key]
                    d = {k: val(v) for k, v in g.attrs.items()}
                    d.update({k: g[k][()] for k in g.keys()})
                    stores[name][ch] = d
        hist = {k: f["history"][k][()] for k in f["history"].keys()} if "history" in f else None
        res = StochasticResult(
            channels=chans, outputs=tuple(o for o in a["outputs"].split(",") if o), fs=a["fs"],
            dt=a["dt"], t_start=a["t_start"], transient=a["transient"], duration=a["duration"],
            method=a["method"], seed=a["seed"],
            model_parameters={k: val(v) for k, v in f["model"].attrs.items()},
            excitation_description={k: val(v) for k, v in f["excitation"].attrs.items()},
            nlbeam_version=a["nlbeam_version"], psd_data=stores["psd"], pdf_data=stores["pdf"],
            moment_data=stores["moments"], history=hist, n_impacts=a["n_impacts"],
            n_steps=a["n_steps"], n_chunks=a["n_chunks"], n_samples=a["n_samples"],
            min_steps_per_contact=a["min_steps_per_contact"], wall_time=a["wall_time"],
            success=bool(a["success"]), message=a["message"],
            n_impacts_transient=a.get("n_impacts_transient", 0),  # absent in older files
            contact_fraction=np.atleast_1d(np.asarray(a.get("contact_fraction", []), float)))
    return res
