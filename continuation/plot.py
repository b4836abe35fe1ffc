"""Alias of ``nlbeam.app.plots.frequency_response`` (all figures live on the application
floor), kept for the name users import; matplotlib is imported when a figure is drawn."""
from nlbeam.app.plots.frequency_response import plot_frequency_response

__all__ = ["plot_frequency_response"]
