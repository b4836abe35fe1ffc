"""The paper's Figure 2: contact force against indentation, measured and fitted."""
from __future__ import annotations

import numpy as np


def plot_contact_fit(fit, delta, rate, force, *, ax=None, max_collisions=8, path=None):
    """Measured force (points) and the fitted law (lines) against indentation, one colour per
    collision (the first ``max_collisions``). delta m, rate m/s, force N as given to
    ``nlbeam.identify.identify_contact``. ``ax``: draw there (else a new figure); ``path``:
    also write the figure (then closed if this call opened it). Returns the Figure."""
    import matplotlib.pyplot as plt

    from nlbeam.identify import collisions

    opened = ax is None
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 4.2))
    else:
        fig = ax.figure
    cs = collisions(delta, rate, force)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, c in enumerate(cs[:max_collisions]):
        col = colours[i % len(colours)]
        ax.plot(c.delta * 1e6, c.force, ".", ms=3, color=col,
                label=f"measured, delta'- = {c.rate_onset:.3g} m/s")
        ax.plot(c.delta * 1e6, fit.force(c.delta, c.rate, c.rate_onset), "-", lw=1, color=col)
    ax.plot([], [], "k-", lw=1, label=f"fitted {fit.law} ({fit.method})")
    ax.set_xlabel("indentation delta [um]")
    ax.set_ylabel("contact force F [N]")
    e = "" if fit.e is None else f", e = {fit.e:.3f}"
    ax.set_title(f"K_hertz = {fit.K_hertz:.4g} N/m^1.5{e}", fontsize=10)
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=min(0.0, float(np.min(np.concatenate([c.force for c in cs])))))
    ax.legend(fontsize=7, loc="upper left", frameon=False)
    from .files import finish_figure

    return finish_figure(fig, path, opened)
