"""Alias of ``nlbeam.app.plots.stochastic`` (all figures live on the application floor),
kept for the names users import; matplotlib is imported when a figure is drawn."""
from nlbeam.app.plots.stochastic import (channel_psds, excitation_psd, pdf, response_psd,
                                         time_history)

__all__ = ["excitation_psd", "response_psd", "pdf", "time_history", "channel_psds"]
