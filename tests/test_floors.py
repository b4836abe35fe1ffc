"""The floors of the house, and imports running downward only.

    3  nlbeam.app.*                  command line, scenes, comparison, sweeps, files, plots
    2  continuation.*, stochastic.*  the analyses (never each other)
    1  nlbeam.*                      models, excitations, the integrator
    0  nlbeam._kernels*, nlbeam._validate, nlbeam.vocabulary   leaves of the core

Every import statement of every module of the three packages (at module level and inside
function bodies) is read with ``ast``; a module may import its own floor or lower ones. The
only upward imports are listed in ``UPWARD``, each with its reason. matplotlib, h5py and dask
are imported on the top floor only, and importing the analyses loads none of them.
"""
import ast
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGES = ("nlbeam", "continuation", "stochastic")
HEAVY = ("matplotlib", "h5py", "dask", "distributed")

#: the upward imports there are, in one place: (importer, imported, where, reason);
#: where = "module" (module level) or "function" (inside a function body only)
UPWARD = (
    ("nlbeam.io", "nlbeam.app.files", "module",
     "alias kept for the name users import (nlbeam.io.atomic_path)"),
    ("nlbeam.compare", "nlbeam.app.compare", "module",
     "alias kept for the name users import (nlbeam.compare.map_peaks)"),
    ("nlbeam.compare", "nlbeam.app.plots.compare", "module",
     "alias kept for the name users import (nlbeam.compare.plot_comparison)"),
    ("nlbeam.scenes", "nlbeam.app.scenes", "module",
     "alias kept for the name users import (nlbeam.scenes.run_scene)"),
    ("nlbeam.sweeps", "nlbeam.app.sweeps", "module",
     "alias kept for the name users import (nlbeam.sweeps.run_jobs)"),
    ("nlbeam.cli", "nlbeam.app.cli", "module",
     "alias kept for the name users import (nlbeam.cli.main)"),
    ("continuation.plot", "nlbeam.app.plots.frequency_response", "module",
     "alias kept for the name users import (continuation.plot.plot_frequency_response)"),
    ("stochastic.plot", "nlbeam.app.plots.stochastic", "module",
     "alias kept for the name users import (stochastic.plot.response_psd, ...)"),
    ("continuation.diagram", "nlbeam.app.files.frequency_response_hdf5", "function",
     "FrequencyResponse.save and continuation.load delegate to the HDF5 file floor"),
    ("stochastic.simulate", "nlbeam.app.files.stochastic_hdf5", "function",
     "StochasticResult.save and stochastic.load delegate to the HDF5 file floor"),
    ("continuation.curve", "nlbeam.app.files.curves_hdf5", "function",
     "BifurcationCurve.save and continuation.load_curves delegate to the HDF5 file floor"),
    ("continuation.chart", "nlbeam.app.files.curves_hdf5", "function",
     "StabilityChart.save delegates to the HDF5 file floor"),
    ("nlbeam.pool", "nlbeam.app.sweeps", "function",
     "Pool(scheduler=...) connects through the application floor's Dask client (dask is "
     "imported on the top floor only)"),
)


def floor(module):
    """Floor number of a module of the project, None for anything else."""
    top = module.split(".")[0]
    if top not in PACKAGES:
        return None
    if module == "nlbeam.app" or module.startswith("nlbeam.app."):
        return 3
    if top in ("continuation", "stochastic"):
        return 2
    if module in ("nlbeam._validate", "nlbeam.vocabulary") or module == "nlbeam._kernels" \
            or module.startswith("nlbeam._kernels."):
        return 0
    return 1


def _modules(root=ROOT):
    """[(module name, path)] of every .py file of the packages."""
    out = []
    for pkg in PACKAGES:
        for folder, dirs, files in os.walk(os.path.join(root, pkg)):
            dirs[:] = sorted(d for d in dirs if d != "__pycache__")
            for f in sorted(files):
                if f.endswith(".py"):
                    rel = os.path.relpath(os.path.join(folder, f), root)[:-3].split(os.sep)
                    if rel[-1] == "__init__":
                        rel = rel[:-1]
                    out.append((".".join(rel), os.path.join(folder, f)))
    return out


def _is_module(name, root=ROOT):
    path = os.path.join(root, *name.split("."))
    return os.path.isfile(path + ".py") or os.path.isfile(os.path.join(path, "__init__.py"))


def imports(module, path, root=ROOT):
    """[(imported module, 'module' | 'function', line)] of the import statements of a file;
    ``from X import y`` gives X.y when that is a module, else X."""
    tree = ast.parse(open(path, encoding="utf-8").read(), path)
    in_function = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            for inner in ast.walk(node):
                if inner is not node:
                    in_function.add(id(inner))
    package = module if path.endswith("__init__.py") else module.rpartition(".")[0]
    out = []
    for node in ast.walk(tree):
        where = "function" if id(node) in in_function else "module"
        if isinstance(node, ast.Import):
            out += [(a.name, where, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module
            for a in node.names:
                sub = f"{source}.{a.name}"
                out.append((sub if _is_module(sub, root) else source, where, node.lineno))
    return out


def violations(root=ROOT):
    """Upward imports not in UPWARD, sibling analyses importing each other, and heavy
    libraries imported below the top floor, as readable lines."""
    allowed = {(a, b): where for a, b, where, _ in UPWARD}
    bad = []
    for module, path in _modules(root):
        f_from = floor(module)
        for target, where, line in imports(module, path, root):
            at = f"{os.path.relpath(path, root)}:{line}: {module} imports {target}"
            top = target.split(".")[0]
            if top in HEAVY and f_from != 3:
                bad.append(f"{at} ({top} only on the application floor)")
                continue
            f_to = floor(target)
            if f_to is None:
                continue
            key = next(((a, b) for a, b in allowed
                        if module == a and (target == b or target.startswith(b + "."))), None)
            if f_to > f_from:
                if key is None:
                    bad.append(f"{at} (floor {f_from} imports floor {f_to})")
                elif allowed[key] == "function" and where != "function":
                    bad.append(f"{at} (allowed inside a function body only)")
            elif f_from == f_to == 2 and top != module.split(".")[0]:
                bad.append(f"{at} (continuation and stochastic never import each other)")
    return bad


def test_imports_run_downward_only():
    bad = violations()
    assert not bad, "\n".join(bad)


def test_every_listed_upward_import_exists():
    """UPWARD names what is there: an entry that no longer occurs is removed from the list."""
    found = {(m, t, w) for m, p in _modules() for t, w, _ in imports(m, p)}
    for importer, imported, where, _ in UPWARD:
        assert any(m == importer and (t == imported or t.startswith(imported + "."))
                   and w == where for m, t, w in found), (importer, imported, where)


def test_the_floor_walk_sees_a_deferred_upward_import(tmp_path):
    """The walk reads function bodies and relative imports: a core module importing the
    analyses inside a function, and an analysis importing its sibling, are both found."""
    for pkg in PACKAGES:
        (tmp_path / pkg).mkdir()
        (tmp_path / pkg / "__init__.py").write_text("")
    (tmp_path / "nlbeam" / "app").mkdir()
    (tmp_path / "nlbeam" / "app" / "__init__.py").write_text("")
    (tmp_path / "nlbeam" / "app" / "plots.py").write_text("import matplotlib\n")
    (tmp_path / "nlbeam" / "helper.py").write_text(
        "def f():\n    import continuation\n    from .app import plots\n")
    (tmp_path / "stochastic" / "sim.py").write_text("from continuation import x\n")
    (tmp_path / "continuation" / "io.py").write_text("def save():\n    import h5py\n")
    bad = violations(str(tmp_path))
    assert any("nlbeam.helper imports continuation (floor 1 imports floor 2)" in b for b in bad)
    assert any("nlbeam.helper imports nlbeam.app.plots (floor 1 imports floor 3)" in b
               for b in bad)
    assert any("stochastic.sim imports continuation (continuation and stochastic" in b
               for b in bad)
    assert any("continuation.io imports h5py (h5py only on" in b for b in bad)
    assert len(bad) == 4, bad


def _loaded(code):
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", code + "; import sys; print(' '.join(sorted("
                          "m for m in sys.modules)))"],
                         capture_output=True, text=True, cwd=ROOT, env=env, check=True)
    return set(out.stdout.split())


@pytest.mark.parametrize("code", ["import continuation, stochastic",
                                  "import nlbeam; nlbeam.BeamImpact; nlbeam.integrate"])
def test_the_analyses_load_no_plotting_files_or_dask(code):
    loaded = _loaded(code)
    assert not {m for m in loaded if m.split(".")[0] in HEAVY}, sorted(loaded)
    assert "scipy.optimize" not in loaded
    assert not {m for m in loaded if m.startswith("nlbeam.app")}


def test_light_helpers_load_nothing_heavy():
    for code in ("import nlbeam.io", "import nlbeam.vocabulary", "import nlbeam"):
        loaded = _loaded(code)
        assert not loaded & {"numpy", "numba", "scipy", "continuation", "stochastic"}, code
