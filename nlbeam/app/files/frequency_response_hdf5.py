"""A frequency-response diagram (``continuation.FrequencyResponse``) as an HDF5 file.

Attributes: version, amplitude, parameter, p_range, wall_time, n_points, ``model.<name>``,
``settings.<name>``. Groups: ``branches/NNNN`` (attributes order, parameter, origin, ends;
datasets values, frequency, amplitude, xmax, stable, multipliers, state0, states, boundaries,
xmax_error, multipliers_error, error_sampled, the last ones only where computed),
``bifurcations`` (one dataset per field, NaN rows where a multiplier, state or contact memory
is absent; ``error``, the integration's error estimate, was ``integrator_error`` in older
files; ``refine_status`` ('' / 'refined' / 'failed: <reason>') and ``refined/<field>`` (the
continuation.refine.Refined records: value, tolerance, digits; values, extrapolated, ratios,
seconds NaN-padded; absent in older files)), ``superharmonics``.
"""
from __future__ import annotations

import h5py
import numpy as np

from continuation.diagram import Bifurcation, Branch, FrequencyResponse, Superharmonic
from continuation.refine import Refined

from .stamped_hdf5 import read_result, write_result

__all__ = ["save_frequency_response", "load_frequency_response"]

FORMAT = "nlbeam.frequency_response"  # and version: see stamped_hdf5.FORMATS


def save_frequency_response(frc, path):
    """Write ``frc`` (a continuation.FrequencyResponse) to HDF5 at ``path``: built in
    memory, stamped with format and checksums, then written atomically (a temporary file in
    the same folder, then os.replace; the usual file mode under the umask). A failure
    leaves nothing and raises one OSError line."""
    with write_result(path, FORMAT) as tmp:  # in memory; stamped; then to disk atomically
        with h5py.File(tmp, "w") as h:
            h.attrs["version"] = frc.version
            h.attrs["amplitude"] = frc.amplitude
            h.attrs["parameter"] = frc.parameter
            h.attrs["p_range"] = np.asarray(frc.p_range, dtype=float)
            h.attrs["wall_time"] = frc.wall_time
            h.attrs["n_points"] = frc.n_points
            for k, v in frc.model_parameters.items():
                h.attrs[f"model.{k}"] = v
            for k, v in frc.settings.items():
                h.attrs[f"settings.{k}"] = "None" if v is None else v
            g = h.create_group("branches")
            for i, b in enumerate(frc.branches):
                gb = g.create_group(f"{i:04d}")
                gb.attrs["order"] = b.order
                gb.attrs["parameter"] = b.parameter
                gb.attrs["origin"] = b.origin
                gb.attrs["ends"] = np.array([str(e) for e in b.ends], dtype="S64")
                for name in ("values", "frequency", "amplitude", "xmax", "stable",
                             "multipliers", "state0", "states", "boundaries", "xmax_error",
                             "multipliers_error", "error_sampled"):
                    if getattr(b, name) is not None:  # stable, multipliers: None without
                        gb.create_dataset(name, data=np.asarray(getattr(b, name)))
            gf = h.create_group("bifurcations")
            bif = frc.bifurcations
            gf.create_dataset("kind", data=np.array([b.kind for b in bif], dtype="S16"))
            gf.create_dataset("note", data=np.array([b.note.encode() for b in bif],
                                                    dtype=h5py.string_dtype()))
            for name in ("frequency", "value", "xmax", "order", "branch", "tolerance",
                         "error"):
                gf.create_dataset(name, data=np.array([getattr(b, name) for b in bif],
                                                      dtype=float))
            n2 = max([len(b.multipliers) for b in bif if b.multipliers is not None],
                     default=0)
            mu = np.full((len(bif), n2), np.nan, dtype=complex)  # NaN: not computed
            for i, b in enumerate(bif):
                if b.multipliers is not None:
                    mu[i, :len(b.multipliers)] = b.multipliers
            gf.create_dataset("multipliers", data=mu)
            n2 = max([len(b.state0) for b in bif if b.state0 is not None], default=0)
            st = np.full((len(bif), n2), np.nan)
            for i, b in enumerate(bif):
                if b.state0 is not None:
                    st[i] = b.state0
            gf.create_dataset("state0", data=st)
            n3 = max([b.disc0.size for b in bif if b.disc0 is not None], default=0)
            dc = np.full((len(bif), n3), np.nan)  # NaN: out of contact at t = 0
            for i, b in enumerate(bif):
                if b.disc0 is not None:
                    dc[i] = np.ravel(b.disc0)
            gf.create_dataset("disc0", data=dc)
            _save_refined(gf, bif)
            gs = h.create_group("superharmonics")
            for name in ("frequency", "xmax", "harmonic", "branch", "ratio", "tolerance"):
                gs.create_dataset(name, data=np.array([getattr(s, name) for s in
                                                       frc.superharmonics], dtype=float))


def load_frequency_response(path):
    """Read a continuation.FrequencyResponse written by ``save_frequency_response``, after
    checking format and checksums (``stamped_hdf5.read_result``: ResultFileError says what
    is wrong in one line)."""
    def s(v):
        return v.decode() if isinstance(v, bytes) else (v.item() if hasattr(v, "item") else v)

    with read_result(path, FORMAT) as h:
        a = h.attrs
        model = {k[6:]: s(a[k]) for k in a if k.startswith("model.")}
        settings = {k[9:]: s(a[k]) for k in a if k.startswith("settings.")}
        frc = FrequencyResponse(model_parameters=model, amplitude=float(a["amplitude"]),
                                parameter=s(a["parameter"]), p_range=tuple(a["p_range"]),
                                settings=settings, wall_time=float(a["wall_time"]),
                                n_points=int(a["n_points"]), version=s(a["version"]))
        for key in sorted(h["branches"]):
            gb = h["branches"][key]
            frc.branches.append(Branch(
                order=int(gb.attrs["order"]), parameter=s(gb.attrs["parameter"]),
                origin=s(gb.attrs["origin"]),
                ends=tuple(e.decode() for e in gb.attrs["ends"]) if "ends" in gb.attrs
                else ("", ""),
                **{n: gb[n][()] if n in gb else None
                   for n in ("values", "frequency", "amplitude", "xmax", "stable",
                             "multipliers", "state0", "states", "boundaries", "xmax_error",
                             "multipliers_error", "error_sampled")}))
        gf = h["bifurcations"]
        for i in range(len(gf["kind"])):
            frc.bifurcations.append(Bifurcation(
                kind=gf["kind"][i].decode(), frequency=float(gf["frequency"][i]),
                value=float(gf["value"][i]), xmax=float(gf["xmax"][i]),
                order=int(gf["order"][i]), branch=int(gf["branch"][i]),
                tolerance=float(gf["tolerance"][i]),
                multipliers=None if np.all(np.isnan(gf["multipliers"][i]))
                and gf["multipliers"].shape[1] else gf["multipliers"][i],
                error=float(gf["error"][i]) if "error" in gf else float(
                    gf["integrator_error"][i]) if "integrator_error" in gf else float("nan"),
                note=s(gf["note"][i]) if "note" in gf else "",
                state0=gf["state0"][i],
                disc0=gf["disc0"][i].reshape(-1, 2) if "disc0" in gf and gf["disc0"].shape[1]
                and not np.all(np.isnan(gf["disc0"][i])) else None))
        _load_refined(gf, frc.bifurcations)
        gs = h["superharmonics"]
        for i in range(len(gs["frequency"])):
            frc.superharmonics.append(Superharmonic(
                frequency=float(gs["frequency"][i]), xmax=float(gs["xmax"][i]),
                harmonic=int(gs["harmonic"][i]), branch=int(gs["branch"][i]),
                **{n: float(gs[n][i]) for n in ("ratio", "tolerance") if n in gs}))
    return frc


_REFINED_SCALARS = ("value", "tolerance", "digits")
_REFINED_ARRAYS = ("values", "extrapolated", "ratios", "seconds")


def _save_refined(gf, bif):
    """refine_status of every bifurcation and its Refined record (NaN where not refined)."""
    gf.create_dataset("refine_status", data=np.array(
        [getattr(b, "refine_status", "").encode() for b in bif], dtype=h5py.string_dtype()))
    rec = [b.refined for b in bif]
    g = gf.create_group("refined")
    for name in _REFINED_SCALARS:
        g.create_dataset(name, data=np.array([getattr(r, name) if r is not None else np.nan
                                              for r in rec], dtype=float))
    for name in _REFINED_ARRAYS:
        n = max([len(getattr(r, name)) for r in rec if r is not None], default=0)
        a = np.full((len(rec), n), np.nan)
        for i, r in enumerate(rec):
            if r is not None:
                a[i, :len(getattr(r, name))] = getattr(r, name)
        g.create_dataset(name, data=a)


def _load_refined(gf, bif):
    """Set refine_status and refined (a Refined without its Integrator levels) from ``gf``."""
    if "refine_status" not in gf:  # written before refinements were saved
        return
    st = gf["refine_status"]
    g = gf["refined"]
    for i, b in enumerate(bif):
        b.refine_status = st[i].decode() if isinstance(st[i], bytes) else str(st[i])
        if b.refine_status != "refined":
            continue
        arrays = {}
        for name in _REFINED_ARRAYS:
            row = g[name][i]
            arrays[name] = row[~np.isnan(row)]
        b.refined = Refined(b.kind, b.order, arrays["values"], arrays["extrapolated"],
                            *(float(g[n][i]) for n in _REFINED_SCALARS), arrays["ratios"],
                            arrays["seconds"], (), b.state0)
