"""The estimator set of one record, shared by ``simulate`` and ``analyze``: one WelchPSD,
StreamingHistogram and StreamingMoments per channel, fed block by block, and their results
stored into a ``StochasticResult``."""
from __future__ import annotations

from .estimators import StreamingHistogram, StreamingMoments, WelchPSD

__all__ = ["make_estimators", "feed", "store_results"]


def make_estimators(channels, outputs, fs, psd_resolution, pdf_edges, pdf_bins, batch):
    """{channel: {output: estimator}}: Welch PSD at ``psd_resolution`` Hz for sampling
    frequency ``fs`` Hz, histogram on ``pdf_edges`` (or ``pdf_bins`` bins chosen from the
    first block), moments; ``batch`` samples per fine batch of the standard errors."""
    est = {}
    for ch in channels:
        e = {}
        if "psd" in outputs:
            e["psd"] = WelchPSD(fs, psd_resolution)
        if "pdf" in outputs:
            e["pdf"] = StreamingHistogram(pdf_edges, bins=pdf_bins, batch_size=batch)
        if "moments" in outputs:
            e["moments"] = StreamingMoments(batch_size=batch)
        est[ch] = e
    return est


def feed(estimators, data):
    """Feed the next consecutive samples ``data`` of one channel to its ``estimators``."""
    for e in estimators.values():
        e.update(data)


def store_results(res, est, min_window=None):
    """Fill ``res.psd_data``, ``pdf_data``, ``moment_data`` from ``est``; ``min_window``:
    least samples per window of the standard errors (a known slow time scale), or None."""
    for ch, e in est.items():
        if "psd" in e:
            res.psd_data[ch] = e["psd"].result()
        if "pdf" in e:
            res.pdf_data[ch] = e["pdf"].result(min_window=min_window)
        if "moments" in e:
            res.moment_data[ch] = e["moments"].result(min_window=min_window)
