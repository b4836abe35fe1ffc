"""All figures of the toolkit (matplotlib is imported inside the functions, so importing a
plot module loads nothing heavy).

- ``frequency_response``: ``plot_frequency_response`` (the paper's Figure 4 style);
  ``continuation.plot`` re-exports it.
- ``stochastic``: ``excitation_psd``, ``response_psd``, ``pdf``, ``time_history``,
  ``channel_psds``; ``stochastic.plot`` re-exports them.
- ``compare``: ``plot_comparison`` (PSD peaks against the diagram); ``nlbeam.compare``
  re-exports it.
- ``scene``: the figure kinds of a scene file (frc, excitation_psd, pdf, history, psd,
  compare).
- ``files``: ``save_figure`` (atomic, then closed) and ``files_backend`` (Agg unless pyplot is
  already in use).
"""
