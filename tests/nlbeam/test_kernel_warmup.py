"""The integration kernels are compiled once per machine and loaded everywhere else: one
signature per kernel whatever the model and excitation, the variational kernel never touched
by a run without monodromies, and pool workers forked after nlbeam.app.warmup.prepare_kernels
compiling nothing. Counted in fresh processes (numba's per-dispatcher cache hits and
misses), not timed."""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
from scipy.linalg import expm

import nlbeam
from nlbeam.integrate import compile_kernels

from helpers import TINY_STOCHASTIC

_REPORT = """
import json
import os
import numba
import nlbeam._kernels as K
import stochastic._kernels as S

def report():
    out = {}
    for mod in (K.loop, K.excite, K.field, S):
        for name, d in vars(mod).items():
            if isinstance(d, numba.core.registry.CPUDispatcher) and d.py_func.__module__ == \\
                    mod.__name__:
                st = d.stats
                out[name] = [len(d.signatures), sum(st.cache_hits.values()),
                             sum(st.cache_misses.values())]
    return out
"""


def _run(code):
    """The JSON printed last by ``code`` run in a fresh interpreter."""
    out = subprocess.run([sys.executable, "-c", _REPORT + textwrap.dedent(code)],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.splitlines()[-1])


def _cached():
    # both kernels in numba's disk cache (compiled here if this is the first use)
    compile_kernels(nlbeam.BeamImpact.paper(), False)
    compile_kernels(nlbeam.BeamImpact.paper(), True)


def test_records_never_load_the_variational_kernel():
    _cached()
    got = _run("""
        import nlbeam, stochastic
        m = nlbeam.ModalBeam.paper(n_modes=2)
        nlbeam.integrate(m, nlbeam.Harmonic(1e-4, 30.0), 0.05)
        nlbeam.flow(nlbeam.BeamImpact.paper(), nlbeam.CosineSum([20.0], [1e-4], [0.0]),
                    [0.0, 0.0], 0.0, 0.05)
        stochastic.simulate(m, stochastic.BandLimitedNoise((0.0, 100.0), rms=1e-4, seed=1),
                            0.5, 0.1, method="rk4", psd_resolution=4.0)
        print(json.dumps(report()))
    """)
    assert got["integrate_plain"] == [1, 1, 0]   # one signature, loaded, not compiled
    assert got["integrate_var"] == [0, 0, 0]     # never loaded


def test_workers_forked_after_prepare_kernels_compile_nothing():
    _cached()
    got = _run("""
        import os
        from nlbeam.app.warmup import prepare_kernels
        from nlbeam.pool import Pool
        import nlbeam
        paper = {"name": "BeamImpact"}
        records = [{"analysis": "stochastic", "model": paper}] * 2
        n_records = prepare_kernels(records)
        after_records = report()
        n_all = prepare_kernels(records + [{"analysis": "periodic", "model": paper,
                                           "periodic": {"stability": True}}])
        after = report()

        def in_worker(_):
            f = nlbeam.flow(nlbeam.ModalBeam.paper(n_modes=3), nlbeam.Harmonic(1e-4, 30.0),
                            [0.0] * 6, 0.0, 0.02, monodromy=True)
            k = nlbeam.BeamImpact.paper().kernels()
            return [os.getpid(), sum(k.integrate_var.stats.cache_misses.values()),
                    sum(k.integrate_var.stats.cache_hits.values()), f.monodromy.shape[0]]

        with Pool(2) as pool:
            workers = pool.map(in_worker, [0, 1, 2, 3])
        print(json.dumps([n_records, after_records, n_all, after, workers, os.getpid()]))
    """)
    n_records, after_records, n_all, after, workers, pid = got
    assert n_records == 1 and after_records["integrate_plain"] == [1, 1, 0]
    assert after_records["integrate_var"] == [0, 0, 0]   # records need no monodromy
    assert n_all == 2 and after["integrate_var"] == [1, 1, 0]   # loaded, not compiled
    assert {w[0] for w in workers} - {pid}               # workers are other processes ...
    # ... that inherited the kernel with its counts: neither compiled nor loaded it again
    assert all(w[1:] == [0, 1, 6] for w in workers)


def test_a_scene_leaves_one_signature_per_kernel(tmp_path):
    _cached()
    scene = tmp_path / "scene.toml"
    scene.write_text(textwrap.dedent("""
        title = "one signature"
        [periodic]
        amplitude = 1e-4
        f_range = [42.0, 45.0]
        orders = [1]
        n_grid = 3
        [[figure]]
        kind = "frc"
        file = "frc.png"
        [[figure]]
        kind = "psd"
        file = "psd.png"
    """) + TINY_STOCHASTIC)
    got = _run(f"""
        from nlbeam.scenes import run_scene
        run_scene({str(scene)!r}, {str(tmp_path / "out")!r}, quiet=True, workers=1)
        print(json.dumps(report()))
    """)
    assert got["integrate_plain"][0] == 1 and got["integrate_var"][0] == 1
    assert got["integrate_plain"][2] == 0 and got["integrate_var"][2] == 0  # none compiled
    several = {name: v for name, v in got.items() if v[0] > 1}
    assert not several, f"kernels compiled for more than one argument type: {several}"


_TINY = '''
from numba import njit

@njit(cache=True)
def tiny(x):
    return 3.0 * x + 1.0
'''


def _tiny_run(tmp_path, cache, code):
    """The JSON printed last by ``code`` in a fresh interpreter that imports the module
    ``tiny_kernel`` (written into tmp_path) with numba's cache in ``cache``."""
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, cwd=tmp_path,
                         env=dict(os.environ, NUMBA_CACHE_DIR=str(cache),
                                  PYTHONPATH=os.pathsep.join([str(tmp_path)] + sys.path)))
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.splitlines()[-1])


def test_a_kernel_compiled_with_another_numba_cache_folder_is_adopted_and_loaded(tmp_path):
    # what prepare_kernels does with the variational kernel compiled in a second process:
    # that process's cache entry copied into this process's folder, then loaded, not compiled
    (tmp_path / "tiny_kernel.py").write_text(_TINY)
    theirs, mine = tmp_path / "theirs", tmp_path / "mine"
    there = _tiny_run(tmp_path, theirs, """
        import json
        from tiny_kernel import tiny
        tiny(2.0)
        print(json.dumps([tiny._cache._cache_path, sum(tiny.stats.cache_misses.values())]))
    """)
    assert there[1] == 1   # compiled there
    here = _tiny_run(tmp_path, mine, f"""
        import json
        from nlbeam.app.warmup import adopt_cached
        from tiny_kernel import tiny
        n = adopt_cached(tiny, {there[0]!r})
        again = adopt_cached(tiny, {there[0]!r})   # the same entry: overwritten, not added
        value = tiny(2.0)
        print(json.dumps([n, again, value, sum(tiny.stats.cache_hits.values()),
                          sum(tiny.stats.cache_misses.values()), len(tiny.signatures)]))
    """)
    assert here == [1, 1, 7.0, 1, 0, 1]   # loaded from the adopted entry, nothing compiled
    # an entry of another source (the file edited since) is not adopted: compiled anew
    (tmp_path / "tiny_kernel.py").write_text(_TINY.replace("3.0 * x", "4.0 * x") + "\n")
    edited = _tiny_run(tmp_path, tmp_path / "third", f"""
        import json
        from nlbeam.app.warmup import adopt_cached
        from tiny_kernel import tiny
        n = adopt_cached(tiny, {there[0]!r})
        print(json.dumps([n, tiny(2.0), sum(tiny.stats.cache_misses.values())]))
    """)
    assert edited == [0, 9.0, 1]


_TOY_LOOPS = '''
import numpy as np
from numba import njit


@njit(cache=True)
def field(x, wn, zeta):
    return np.array([x[1], -wn * wn * x[0] - 2.0 * zeta * wn * x[1]])


@njit(cache=True)
def rk4(x, h, wn, zeta):
    k1 = field(x, wn, zeta)
    k2 = field(x + 0.5 * h * k1, wn, zeta)
    k3 = field(x + 0.5 * h * k2, wn, zeta)
    k4 = field(x + h * k3, wn, zeta)
    return x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def _loop_for(want_var):
    # as nlbeam._kernels.loop._loop_for: one factory, two loops of one signature sharing the
    # step functions; the monodromy M integrated only by the variational one
    def _loop(x0, wn, zeta, T, n, M):
        h = T / n
        x = x0.copy()
        for _ in range(n):
            if want_var:
                for j in range(2):   # the variational equations of a linear field: its
                    M[:, j] = rk4(M[:, j], h, wn, zeta)   # flow on each column of M
            x = rk4(x, h, wn, zeta)
        return x
    _loop.__name__ += "_var" if want_var else "_plain"
    _loop.__qualname__ = _loop.__name__
    return njit(cache=True)(_loop)


loop_plain = _loop_for(False)
loop_var = _loop_for(True)
'''

_TOY_RUN = """
import json
import numpy as np
from toy_loops import loop_plain, loop_var
x = {which}(np.array([1e-3, 0.0]), {wn}, {zeta}, {T}, 2000, np.eye(2))
d = {which}
print(json.dumps([d._cache._cache_path, x.tolist(), None, sum(d.stats.cache_misses.values())]))
"""


def test_a_variational_loop_compiled_in_a_second_process_integrates_the_monodromy(tmp_path):
    # session 11's empty diagrams: the variational kernel compiled in a second process and
    # loaded here beside the plain one compiled here ran the plain loop (both loops were one
    # closure, whose compiled name came out the same in both processes), so the monodromy
    # stayed unintegrated. The mechanism on a toy of the same shape (one factory, two loops of
    # one signature, shared step functions; seconds to compile, not the 92 s of nlbeam's
    # kernels): the variational loop compiled in another process with its own numba cache,
    # adopted here (adopt_cached, as prepare_kernels does) and loaded beside the plain one
    # compiled here; the monodromy of a linear oscillator over 0.1 s against its matrix exponential.
    # (The names test_no_two_compiled_functions_share_a_qualified_name checks for nlbeam's
    # own kernels are what makes this work; the real variational kernel's monodromy:
    # test_the_suites_variational_kernel_integrates_the_monodromy.)
    wn, zeta, T = 2 * np.pi * 20.0, 0.02, 0.1
    (tmp_path / "toy_loops.py").write_text(_TOY_LOOPS)
    var = _tiny_run(tmp_path, tmp_path / "theirs",
                    _TOY_RUN.format(which="loop_var", wn=wn, zeta=zeta, T=T))
    assert var[3] == 1   # compiled there
    here = _tiny_run(tmp_path, tmp_path / "mine", f"""
        import json
        import numpy as np
        from nlbeam.app.warmup import adopt_cached
        from toy_loops import loop_plain, loop_var
        n = adopt_cached(loop_var, {var[0]!r})
        x0 = np.array([1e-3, 0.0])
        Mp, Mv = np.eye(2), np.eye(2)
        xp = loop_plain(x0, {wn}, {zeta}, {T}, 2000, Mp)
        xv = loop_var(x0, {wn}, {zeta}, {T}, 2000, Mv)
        st = [sum(d.stats.cache_hits.values()) for d in (loop_plain, loop_var)]
        miss = [sum(d.stats.cache_misses.values()) for d in (loop_plain, loop_var)]
        print(json.dumps([n, st, miss, xp.tolist(), xv.tolist(), Mp.tolist(), Mv.tolist()]))
    """)
    n, hits, misses, xp, xv, Mp, Mv = here
    assert n == 1 and hits == [0, 1] and misses == [1, 0]   # plain compiled here, var loaded
    A = np.array([[0.0, 1.0], [-wn * wn, -2 * zeta * wn]])
    E = expm(A * T)
    scale = np.diag([1.0, wn])   # (m, m/s) -> comparable units
    err = np.linalg.inv(scale) @ (np.array(Mv) - E) @ scale
    # RK4, 2000 steps: ~1e-9 from expm; a monodromy never integrated (the identity): 0.2 off
    assert np.abs(err).max() < 1e-6, (Mv, E)
    assert Mp == np.eye(2).tolist()   # the plain loop leaves M alone ...
    assert xp == xv == var[1]         # ... and both integrate the state as the other process
    assert np.abs(np.array(xv) - E @ [1e-3, 0.0]).max() < 1e-9


def test_the_suites_variational_kernel_integrates_the_monodromy():
    # the kernel the suite uses (compiled or loaded once per machine): the monodromy of a
    # linear oscillator over 0.1 s (a stop far out of reach) against its matrix exponential
    wn, zeta, T = 2 * np.pi * 20.0, 0.02, 0.1
    m = nlbeam.System([[1.0]], [[2 * zeta * wn]], [[wn ** 2]], elements=(
        nlbeam.PiecewiseLinearStop(0, k=1e6, gap=1.0),))
    f = nlbeam.flow(m, nlbeam.Harmonic(1e-4, 25.0), [1e-3, 0.0], 0.0, T, monodromy=True)
    A = np.array([[0.0, 1.0], [-wn * wn, -2 * zeta * wn]])
    scale = np.diag([1.0, wn])
    err = np.linalg.inv(scale) @ (np.asarray(f.monodromy) - expm(A * T)) @ scale
    # RK4 at the default step: 5.2e-7 from expm; a monodromy never integrated: 0.22 off
    assert np.abs(err).max() < 1e-5, (f.monodromy, expm(A * T))


def _compiled_functions():
    """Every numba dispatcher defined at module level in the compiled packages."""
    import importlib
    import pkgutil

    import numba

    import nlbeam._kernels as K

    mods = [importlib.import_module(f"nlbeam._kernels.{m.name}")
            for m in pkgutil.iter_modules(K.__path__)]
    mods += [importlib.import_module(m) for m in ("nlbeam._linalg", "stochastic._kernels")]
    for mod in mods:
        for name, d in vars(mod).items():
            if isinstance(d, numba.core.registry.CPUDispatcher):
                yield f"{mod.__name__}.{name}", d


def test_no_two_compiled_functions_share_a_qualified_name():
    # numba names a function's machine code by module, qualified name, argument types and a
    # count of the compiles in its process: two functions of one name (closures of one
    # factory) compiled in two processes can come out as one symbol, and a process that loads
    # both from the disk cache runs one function's code for both (session 11's variational
    # kernel ran the plain loop). Each function is listed under every name it is imported as.
    seen = {}
    for where, d in _compiled_functions():
        seen.setdefault((d.py_func.__module__, d.py_func.__qualname__), set()).add(id(d))
    shared = {k: len(v) for k, v in seen.items() if len(v) > 1}
    assert not shared, f"compiled functions sharing a qualified name: {shared}"
    assert ("nlbeam._kernels.loop", "_integrate_loop_var") in seen
