"""nlbeam.compare: PSD peaks traced to the periodic diagram.

A synthetic diagram (hand-made branches) and a synthetic PSD with peaks placed where each
kind of explanation predicts them give the known assignment; on the paper model, a narrow
band around twice the harmonic resonance gives a response peak at half the excitation
frequencies that is assigned to the order-2 branch (the paper's stochastic 1/2 subharmonic).
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from nlbeam.compare import map_peaks, plot_comparison, resonances


def _branch(order, f, xmax, stable=True):
    return SimpleNamespace(order=order, frequency=np.asarray(f), xmax=np.asarray(xmax),
                           stable=np.full(len(f), stable))


def _lorentz(f, f0, w, a):
    return a / (1.0 + ((f - f0) / w) ** 2)


@pytest.fixture(scope="module")
def diagram():
    # harmonic branch: main resonance at 40 Hz, a superharmonic bump at 20 Hz (k = 2);
    # an order-2 branch resonating at 90 Hz (response 45 Hz), unstable there
    f1 = np.linspace(5.0, 80.0, 751)
    x1 = 1e-4 + _lorentz(f1, 40.0, 2.0, 1e-3) + _lorentz(f1, 20.0, 0.5, 1e-4)
    f2 = np.linspace(70.0, 100.0, 301)
    x2 = 2e-4 + _lorentz(f2, 90.0, 1.5, 1e-3)
    return SimpleNamespace(branches=[_branch(1, f1, x1), _branch(2, f2, x2, stable=False)],
                           bifurcations=[], superharmonics=[])


def _psd(peaks, rng):
    f = np.arange(0.0, 200.0001, 0.25)
    P = 1e-10 * np.exp(-f / 150.0)
    for f0, a in peaks:
        P = P + _lorentz(f, f0, 0.6, a)
    P *= rng.chisquare(60, f.size) / 60  # Welch-like scatter, 60 dof
    return f, P


def test_resonances_of_the_synthetic_diagram(diagram):
    res = {(r.kind, r.order, round(r.frequency, 1)) for r in resonances(diagram)}
    assert res == {("harmonic", 1, 40.0), ("harmonic", 1, 20.0), ("superharmonic", 2, 20.0),
                   ("subharmonic", 2, 90.0)}


def test_broadband_assignment(diagram):
    rng = np.random.default_rng(1)
    # 127 Hz: inside the broad band, no resonance, not a multiple of 40 or 45.5 Hz
    psd = _psd([(5.0, 2e-9), (40.0, 5e-8), (45.5, 2e-8), (127.0, 3e-9)], rng)
    m = map_peaks(psd, diagram, (0.0, 200.0))
    got = [(round(p.frequency), p.kind, p.order, p.note) for p in m]
    assert got == [(5, "asymmetry", 0, ""), (40, "harmonic", 1, "resonance"),
                   (46, "subharmonic", 2, "resonance"), (127, "unexplained", 0, "")], got
    sub = m[2]
    assert sub.branch_frequency == pytest.approx(90.0, abs=0.2)
    assert sub.stable is False and sub.distance == pytest.approx(0.5, abs=0.3)
    assert m[1].stable is True and m[1].distance < 0.5 and m[1].prominence > 1.0
    assert math.isnan(m[3].branch_frequency) and m[3].stable is None


def test_band_decides_between_explanations(diagram):
    rng = np.random.default_rng(2)
    # excitation 15-25 Hz: a response peak at 40 Hz can only be the superharmonic of
    # order 2 (excited at 20 Hz); the peak at 20 Hz is the harmonic branch's own bump
    psd = _psd([(20.0, 2e-8), (40.0, 1e-8)], rng)
    m = map_peaks(psd, diagram, (15.0, 25.0))
    got = [(round(p.frequency), p.kind, p.order, round(p.branch_frequency)) for p in m]
    assert got == [(20, "harmonic", 1, 20), (40, "superharmonic", 2, 20)], got
    # excitation 85-95 Hz: the 45 Hz peak is the 1/2 subharmonic, not the harmonic
    # resonance nearby (40 Hz lies outside the band and outside the tolerance)
    psd = _psd([(45.0, 2e-8)], rng)
    (p,) = map_peaks(psd, diagram, SimpleNamespace(band=(85.0, 95.0)))
    assert (p.kind, p.order) == ("subharmonic", 2)
    # and with no order-2 branch it is unexplained
    only1 = SimpleNamespace(branches=diagram.branches[:1], bifurcations=[], superharmonics=[])
    (p,) = map_peaks(psd, only1, (85.0, 95.0))
    assert p.kind == "unexplained"


def test_multiples_of_a_stronger_peak_are_superharmonics_of_it(diagram):
    rng = np.random.default_rng(4)
    # broad band: the harmonic resonance at 40 Hz and its 2nd and 3rd multiples (the impact
    # makes the response non-harmonic); 100 Hz is 2.5 x 40: no integer multiple
    psd = _psd([(40.0, 5e-8), (80.0, 4e-9), (120.0, 2e-9), (100.0, 3e-9)], rng)
    m = {round(p.frequency): p for p in map_peaks(psd, diagram, (0.0, 200.0))}
    assert sorted(m) == [40, 80, 100, 120]
    for f, k in ((80, 2), (120, 3)):
        p = m[f]
        assert (p.kind, p.order, p.note) == ("superharmonic", k, "multiple"), p
        assert p.explained_by == m[40].frequency
        assert p.branch_frequency == m[40].branch_frequency and p.stable is True
        assert p.response_frequency == k * m[40].frequency
        assert p.distance == pytest.approx(abs(p.frequency - k * m[40].frequency))
    assert (m[100].kind, m[100].note) == ("unexplained", "")
    # the parent must be the stronger peak: a 40 Hz peak weaker than the 80 Hz one
    # explains nothing there (80 Hz stays unexplained under the broad band)
    psd = _psd([(40.0, 2e-9), (80.0, 4e-8)], rng)
    m = {round(p.frequency): p for p in map_peaks(psd, diagram, (0.0, 200.0))}
    assert (m[40].kind, m[80].kind) == ("harmonic", "unexplained")


def test_multiples_of_a_subharmonic_peak(diagram):
    # narrow band 85-95 Hz: 45 Hz is the 1/2 subharmonic (order-2 branch at 90 Hz); 135 Hz
    # (3/2 of the excitation) is 3 x that peak and keeps the order-2 branch point
    rng = np.random.default_rng(5)
    psd = _psd([(45.0, 3e-8), (135.0, 2e-9)], rng)
    sub, third = map_peaks(psd, diagram, (85.0, 95.0))
    assert (sub.kind, sub.order) == ("subharmonic", 2)
    assert (third.kind, third.order, third.note) == ("superharmonic", 3, "multiple")
    assert third.explained_by == sub.frequency and third.branch == sub.branch == 1
    assert third.branch_frequency == sub.branch_frequency
    assert third.stable is False


def test_forced_response_inside_a_narrow_band(diagram):
    rng = np.random.default_rng(6)
    psd = _psd([(68.0, 1e-8)], rng)
    # narrow band 60-75 Hz, no resonance at 68 Hz: the order-1 response to the band
    (p,) = map_peaks(psd, diagram, (60.0, 75.0))
    assert (p.kind, p.order, p.note) == ("harmonic", 1, "forced"), p
    assert p.frequency == pytest.approx(68.0, abs=0.5)
    # the order-1 branch point nearest the peak (branch grid 0.1 Hz)
    assert p.branch == 0 and p.branch_frequency == pytest.approx(p.frequency, abs=0.051)
    assert p.distance <= p.tolerance and p.stable is True
    # a harmonic excitation at 68 Hz: the same
    from nlbeam import Harmonic
    (p,) = map_peaks(psd, diagram, Harmonic(1e-4, 68.0))
    assert (p.kind, p.note) == ("harmonic", "forced")
    # a broad band holds 68 Hz too, but a flat input makes no peak away from resonance
    (p,) = map_peaks(psd, diagram, (0.0, 200.0))
    assert p.kind == "unexplained"
    # a narrow band that does not hold it
    (p,) = map_peaks(psd, diagram, (20.0, 30.0))
    assert p.kind == "unexplained"
    # beyond the diagram (order-1 branch 5-80 Hz): forced, with no diagram point
    (p,) = map_peaks(_psd([(150.0, 1e-8)], rng), diagram, (145.0, 160.0))
    assert (p.kind, p.note, p.branch) == ("harmonic", "forced", -1)
    assert math.isnan(p.branch_frequency) and p.stable is None


def test_f_range_limits_the_peaks(diagram):
    rng = np.random.default_rng(7)
    psd = _psd([(40.0, 5e-8), (127.0, 3e-9), (190.0, 3e-9)], rng)
    got = [round(p.frequency) for p in map_peaks(psd, diagram, (0.0, 200.0))]
    assert got == [40, 127, 190]
    got = [round(p.frequency) for p in map_peaks(psd, diagram, (0.0, 200.0), f_range=(0.0, 150.0))]
    assert got == [40, 127]
    with pytest.raises(ValueError, match=r"f_range: must be \(low, high\) with 0.0 <= low < high"):
        map_peaks(psd, diagram, f_range=(150.0, 10.0))


def test_flat_noise_has_no_peaks(diagram):
    rng = np.random.default_rng(3)
    assert map_peaks(_psd([], rng), diagram) == []


def test_bad_input_names_the_argument(diagram):
    with pytest.raises(ValueError, match="psd"):
        map_peaks((np.arange(3.0), np.ones(4)), diagram)
    with pytest.raises(ValueError, match="tolerance"):
        map_peaks(_psd([], np.random.default_rng(0)), diagram, tolerance=-1.0)


@pytest.fixture(scope="module")
def paper_subharmonic():
    """Paper model, flat band 78-98 Hz (around twice the harmonic resonance near 43.5 Hz),
    rms 0.1 mm, 20 s; diagram of orders 1 and 2 over 80-95 Hz (a few seconds each)."""
    import warnings

    import continuation
    import nlbeam
    import stochastic

    model = nlbeam.BeamImpact.paper()
    noise = stochastic.BandLimitedNoise(band=(78.0, 98.0), rms=1e-4, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = stochastic.simulate(model, noise, duration=20.0, transient=2.0, outputs=("psd",),
                                  channels=("delta",), psd_resolution=0.5)
        frc = continuation.frequency_response(model, 1e-4, (80.0, 95.0), orders=(1, 2),
                                              n_grid=6)
    return res, frc, noise


def test_paper_model_half_frequency_peak_is_the_order_2_branch(paper_subharmonic, tmp_path):
    res, frc, noise = paper_subharmonic
    m = map_peaks(res.psd("delta"), frc, noise)
    low = [p for p in m if 35.0 < p.frequency < 50.0]
    assert low, [(p.frequency, p.kind) for p in m]
    p = max(low, key=lambda p: p.prominence)
    assert (p.kind, p.order) == ("subharmonic", 2), p
    assert 80.0 < p.branch_frequency < 95.0
    assert p.distance <= p.tolerance
    import matplotlib
    matplotlib.use("Agg")
    fig = plot_comparison(res.psd("delta"), frc, m, excitation=noise, f_max=120.0)
    fig.savefig(tmp_path / "cmp.png")
    assert (tmp_path / "cmp.png").stat().st_size > 1000


def test_a_diagram_without_stability_gives_stable_none(diagram, tmp_path):
    # frequency_response(..., stability=False) leaves every branch's `stable` None
    nostab = SimpleNamespace(branches=[SimpleNamespace(order=b.order, frequency=b.frequency,
                                                       xmax=b.xmax, stable=None)
                                       for b in diagram.branches],
                             bifurcations=[], superharmonics=[])
    rng = np.random.default_rng(8)
    psd = _psd([(40.0, 5e-8), (80.0, 4e-9), (45.5, 2e-8)], rng)
    with_st = map_peaks(psd, diagram, (0.0, 200.0))
    without = map_peaks(psd, nostab, (0.0, 200.0))
    assert [(m.frequency, m.kind, m.order, m.note) for m in with_st] == \
        [(m.frequency, m.kind, m.order, m.note) for m in without]
    assert all(m.stable is None for m in without)
    assert [m.as_row()["stable"] for m in without] == ["", "", ""]
    (forced,) = map_peaks(_psd([(68.0, 1e-8)], rng), nostab, (60.0, 75.0))
    assert forced.note == "forced" and forced.branch == 0 and forced.stable is None
    import matplotlib
    matplotlib.use("Agg")
    plot_comparison(psd, nostab, excitation=(0.0, 200.0)).savefig(tmp_path / "c.png")
    assert (tmp_path / "c.png").stat().st_size > 1000
