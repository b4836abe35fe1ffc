"""Alias of ``nlbeam.app.compare`` (``map_peaks``: PSD peaks -> periodic diagram) and of its
figure ``nlbeam.app.plots.compare.plot_comparison``, kept for the names users import."""
from nlbeam.app.compare import KINDS, PeakMatch, Resonance, find_peaks, map_peaks, resonances
from nlbeam.app.plots.compare import plot_comparison

__all__ = ["PeakMatch", "Resonance", "map_peaks", "find_peaks", "resonances", "plot_comparison",
           "KINDS"]
