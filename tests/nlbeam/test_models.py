"""The models: parameters, sign convention, helpers of the contact laws, bad input."""
import json
import math
import os
import pickle
import subprocess
import sys
import textwrap
import types

import numpy as np
import pytest

import nlbeam
from helpers import cubic_force
from nlbeam import custom as custom_mod


def test_paper_parameters_and_linear_frequency():
    m = nlbeam.BeamImpact.paper()
    assert (m.m, m.k, m.b, m.K_hertz, m.e) == (37.75e-3, 736.3, 0.16, 2.1e8, 0.5)
    assert m.contact == "lankarani-nikravesh"
    assert m.natural_frequency == pytest.approx(22.23, abs=0.01)
    assert m.b / (2 * math.sqrt(m.k * m.m)) == pytest.approx(0.0152, abs=1e-4)


def test_penetrated_beam_at_rest_is_pushed_out_of_the_stop():
    # delta = x - y > 0: the stop must accelerate the beam in -x (out of the stop)
    for law, kw in (("hertz", {}), ("lankarani-nikravesh", {}), ("hunt-crossley", {"mu": 1e5})):
        model = nlbeam.BeamImpact.paper(contact=law, k=0.0, b=0.0, **kw)
        tr = nlbeam.integrate(model, nlbeam.Harmonic(0.0, 10.0), 2e-5, dt=1e-6, x0=[1e-6, 0.0])
        assert tr.force[0, 0] == pytest.approx(2.1e8 * 1e-9, rel=1e-12)
        assert tr.v[-1, 0] < 0 and tr.x[-1, 0] < 1e-6


def test_hertz_stiffness_from_material_and_geometry():
    # two equal PTFE-like spheres: E = 0.5 GPa, nu = 0.46, R = 5 mm
    E, nu, R = 0.5e9, 0.46, 5e-3
    Er = 2 / (2 * (1 - nu ** 2) / E)
    assert nlbeam.hertz_stiffness(E, nu, R, E, nu, R) == \
        pytest.approx(2 / 3 * Er * math.sqrt(R / 2))
    # sphere on a flat: R_r = R
    assert nlbeam.hertz_stiffness(E, nu, R, E, nu, math.inf) == \
        pytest.approx(2 / 3 * Er * math.sqrt(R))


def test_mu_and_e_are_inverse():
    mu = nlbeam.mu_from_e(0.5, 2.1e8, 0.1)
    assert mu == pytest.approx(3 * 2.1e8 * 0.75 / 0.4)
    assert nlbeam.e_from_mu(mu, 2.1e8, 0.1) == pytest.approx(0.5, rel=1e-14)


@pytest.mark.parametrize("kwargs, name", [
    ({"m": -1.0}, "m"), ({"m": 0.0}, "m"), ({"m": float("nan")}, "m"),
    ({"k": -1.0}, "k"), ({"b": float("inf")}, "b"), ({"K_hertz": -2.0}, "K_hertz"),
    ({"e": 0.0}, "e"), ({"e": 1.5}, "e"), ({"contact": "kelvin"}, "contact"),
    ({"contact": "hunt-crossley"}, "mu"),
])
def test_bad_model_parameters_name_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name}:"):
        nlbeam.BeamImpact.paper(**kwargs)


@pytest.mark.parametrize("kwargs, name", [
    ({"law": "kelvin"}, "law"), ({"K": -1.0}, "K"), ({"gap": float("nan")}, "gap"),
    ({"law": "hunt-crossley"}, "mu"), ({"law": "lankarani-nikravesh"}, "e"),
])
def test_bad_contact_parameters_name_the_parameter(kwargs, name):
    kw = dict(dof=0, law="hertz", K=1e8)
    kw.update(kwargs)
    with pytest.raises(ValueError, match=rf"^{name}:"):
        nlbeam.Contact(**kw)


def test_stop_removed_is_valid():
    m = nlbeam.BeamImpact.paper(K_hertz=0.0)
    assert not m.has_events()


@pytest.mark.parametrize("kwargs, name", [
    ({"amplitude": float("nan"), "frequency": 1.0}, "amplitude"),
    ({"amplitude": 1.0, "frequency": 0.0}, "frequency"),
    ({"amplitude": 1.0, "frequency": -3.0}, "frequency"),
])
def test_bad_excitation_names_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name}:"):
        nlbeam.Harmonic(**kwargs)


def test_zero_amplitude_is_valid():
    assert nlbeam.Harmonic(0.0, 10.0).amplitude == 0.0


def test_general_system_validates_matrices():
    with pytest.raises(ValueError, match="^M:"):
        nlbeam.System([[1.0, 0.0], [0.0, -1.0]], np.zeros((2, 2)), np.eye(2))
    with pytest.raises(ValueError, match="^C:"):
        nlbeam.System(np.eye(2), np.zeros((3, 3)), np.eye(2))
    with pytest.raises(ValueError, match="^dof:"):
        nlbeam.System(np.eye(2), np.zeros((2, 2)), np.eye(2), (nlbeam.Contact(5, "hertz", 1.0),))


@pytest.mark.slow
def test_a_custom_jitted_force_equals_the_built_in_cubic_spring():
    # helpers.cubic_force is importable by name: its kernels come from the disk cache after the
    # first run on this machine (nlbeam.custom)
    ex = nlbeam.Harmonic(0.2, 0.15)
    duff = nlbeam.Duffing(m=1.0, b=0.1, k=1.0, k3=1.0)
    custom = nlbeam.System([[1.0]], [[0.1]], [[1.0]], (), "force", y_load=[1.0], yd_load=[0.0],
                           custom_force=cubic_force, custom_params=[1.0])
    a = nlbeam.integrate(duff, ex, 20.0, dt=0.01, x0=[0.3, 0.0])
    b = nlbeam.integrate(custom, ex, 20.0, dt=0.01, x0=[0.3, 0.0])
    np.testing.assert_allclose(b.x, a.x, rtol=0, atol=1e-13)
    fa = nlbeam.flow(duff, ex, [0.3, 0.0], 0.0, 5.0, monodromy=True, dt=0.01)
    fb = nlbeam.flow(custom, ex, [0.3, 0.0], 0.0, 5.0, monodromy=True, dt=0.01)
    np.testing.assert_allclose(fb.monodromy, fa.monodromy, rtol=1e-5, atol=1e-6)
    assert custom.kernels().__name__.startswith("nlbeam._kernels_cached_")


def test_a_worker_process_loads_the_custom_force_kernels_from_the_disk_cache(tmp_path):
    # a model sent to another process (a sweep's or Dask's worker) with its force pickled: the
    # worker finds the kernels compiled here in the disk cache (numba counts a cache hit)
    custom = nlbeam.System([[1.0]], [[0.1]], [[1.0]], (), "force", y_load=[1.0],
                           custom_force=cubic_force, custom_params=[1.0])
    ex = nlbeam.Harmonic(0.2, 0.15)
    here = nlbeam.flow(custom, ex, [0.3, 0.0], 0.0, 1.0, monodromy=True, dt=0.01)  # compiled
    (tmp_path / "model.pkl").write_bytes(pickle.dumps(custom))
    helpers_py = os.path.join(os.path.dirname(os.path.dirname(__file__)), "helpers.py")
    code = textwrap.dedent(f"""
        import importlib.util, json, pickle, sys
        import nlbeam
        spec = importlib.util.spec_from_file_location("helpers", {helpers_py!r})
        sys.modules["helpers"] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules["helpers"])
        with open({str(tmp_path / "model.pkl")!r}, "rb") as f:
            custom = pickle.load(f)
        fl = nlbeam.flow(custom, nlbeam.Harmonic(0.2, 0.15), [0.3, 0.0], 0.0, 1.0,
                         monodromy=True, dt=0.01)
        k = custom.kernels()
        stats = k.integrate_var.stats
        print(json.dumps([k.__name__, sum(stats.cache_hits.values()),
                          sum(stats.cache_misses.values()), fl.state.tolist(),
                          fl.monodromy.tolist()]))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    name, hits, misses, state, mono = json.loads(out.splitlines()[-1])
    assert name == custom.kernels().__name__
    assert (hits, misses) == (1, 0)   # loaded, not compiled
    np.testing.assert_array_equal(state, here.state)   # (JSON keeps floats exactly)
    np.testing.assert_array_equal(mono, here.monodromy)


def test_a_custom_force_that_cannot_be_imported_by_name_is_not_cached():
    from numba import njit

    @njit
    def local(t, x, v, y, yd, params, out):
        out[0] -= x[0]

    where, why = custom_mod.import_path(local)
    assert where is None and "inside a function" in why
    assert custom_mod.cached_folder(local) == (None, why)
    with pytest.warns(RuntimeWarning, match="inside a function.*without a disk cache"):
        k = custom_mod.kernels_for(local)   # (compiles lazily: nothing called here)
    assert k.hook._USER_FORCE is local and k.hook._HAS_USER and not k.hook._CACHE
    assert custom_mod.kernels_for(local) is k   # once per function and process
    # an importable force: a generated copy that imports it by name, cached on disk
    assert custom_mod.import_path(cubic_force) == (("helpers", "cubic_force"), None)
    k = custom_mod.kernels_for(cubic_force)
    assert k.hook._USER_FORCE is cubic_force and k.hook._CACHE
    assert k.__file__.startswith(custom_mod.cache_root())


def test_the_custom_force_cache_key_follows_the_globals_it_reads():
    # numba freezes a force's global constants into the compiled code: a changed constant must
    # give another cached copy, the same source and values the same one
    def force_module(k3):
        mod = types.ModuleType("nlbeam_test_force_module")
        exec("from numba import njit\nK3 = %r\n\n@njit\ndef f(t, x, v, y, yd, params, out):\n"
             "    out[0] -= K3 * x[0] ** 3\n" % k3, mod.__dict__)
        return mod.f

    keys = [custom_mod.cache_key(force_module(k3), "m", "f") for k3 in (1.0, 1.0, 2.0)]
    assert keys[0] == keys[1] != keys[2]
    assert custom_mod.cache_key(cubic_force, "helpers", "cubic_force") != keys[0]


def test_custom_force_must_be_jitted():
    with pytest.raises(ValueError, match="^custom_force:"):
        nlbeam.System([[1.0]], [[0.0]], [[1.0]], (), "force", custom_force=lambda *a: None)
