"""numba's kernel caches are dropped when any kernel source changes (numba itself keys a cache by
the defining file only, so a kernel that inlines an edited function would run the old code)."""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import nlbeam._kernels as kernels
from nlbeam._kernels import stale_cache


def _folder(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    for name, text in (("excite.py", "A = 1\n"), ("loop.py", "B = 2\n")):
        (src / name).write_text(text)
    cache = src / "__pycache__"
    cache.mkdir()
    for name in ("loop.integrate_kernel-10.py311.nbi", "loop.integrate_kernel-10.py311.1.nbc"):
        (cache / name).write_bytes(b"compiled")
    (cache / "loop.cpython-311.pyc").write_bytes(b"bytecode")
    return src, cache


def test_caches_survive_while_the_sources_are_unchanged(tmp_path):
    src, cache = _folder(tmp_path)
    sources = sorted(src.glob("*.py"))
    stale_cache.drop_stale(cache, sources)  # first look: no stamp yet, so nothing is trusted
    (cache / "loop.integrate_kernel-10.py311.nbi").write_bytes(b"compiled again")
    assert stale_cache.drop_stale(cache, sources) == 0
    assert (cache / "loop.integrate_kernel-10.py311.nbi").exists()


def test_an_edited_source_that_another_kernel_inlines_drops_every_cache(tmp_path):
    src, cache = _folder(tmp_path)
    sources = sorted(src.glob("*.py"))
    stale_cache.drop_stale(cache, sources)
    for name in ("loop.integrate_kernel-10.py311.nbi", "loop.integrate_kernel-10.py311.1.nbc"):
        (cache / name).write_bytes(b"compiled from the old excite.py")
    (src / "excite.py").write_text("A = 3\n")  # loop.py itself is untouched
    assert stale_cache.drop_stale(cache, sources) == 2
    assert sorted(p.name for p in cache.iterdir()) == ["kernel_sources.sha256",
                                                       "loop.cpython-311.pyc"]
    # a numba upgrade is a change too
    stale_cache.drop_stale(cache, sources, extra=("numba 0.60",))
    (cache / "x.nbi").write_bytes(b"")
    assert stale_cache.drop_stale(cache, sources, extra=("numba 0.61",)) == 1


def test_a_read_only_cache_folder_is_left_alone(tmp_path):
    src, cache = _folder(tmp_path)
    missing = tmp_path / "no" / "such" / "__pycache__"  # cannot be created: parent missing
    assert stale_cache.drop_stale(missing, sorted(src.glob("*.py"))) == 0


def test_the_package_stamp_is_the_digest_of_todays_kernel_sources():
    here = Path(kernels.__file__).resolve().parent
    stamp = stale_cache.numba_cache_dir(stale_cache.check_package) / stale_cache.STAMP
    if not stamp.exists():  # a read-only install: nothing to check
        return
    import sys

    import numba
    digest = stale_cache.sources_digest(sorted(here.glob("*.py")),
                                        extra=(sys.version, numba.__version__))
    assert stamp.read_text().strip() == digest


def test_the_guarded_folder_is_numbas_cache_folder_under_NUMBA_CACHE_DIR(tmp_path, monkeypatch):
    from numba.core import config
    here = Path(kernels.__file__).resolve().parent
    monkeypatch.setattr(config, "CACHE_DIR", "")
    assert stale_cache.numba_cache_dir(stale_cache.check_package) == here / "__pycache__"
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "numba"))
    folder = stale_cache.numba_cache_dir(stale_cache.check_package)
    assert folder.parent == tmp_path / "numba" and folder.name.startswith("_kernels_")


# a kernel that calls a jitted function of another file, and the package's guard in front
_HELPER = "from numba import njit\n\n\n@njit(cache=True)\ndef value():\n    return {}\n"
_KERNEL = textwrap.dedent("""\
    import sys
    from numba import njit
    if sys.argv[1] == "guarded":
        import stale_cache
        stale_cache.check_package()
    from helper import value


    @njit(cache=True)
    def kernel():
        return value() + 0


    print(kernel())
""")


def test_a_kernel_compiled_from_an_edited_helper_is_not_loaded_from_NUMBA_CACHE_DIR(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "stale_cache.py").write_text(Path(stale_cache.__file__).read_text())
    (pkg / "kern.py").write_text(_KERNEL)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               PYTHONDONTWRITEBYTECODE="1")

    def run(helper_value, how):
        (pkg / "helper.py").write_text(_HELPER.format(helper_value))
        out = subprocess.run([sys.executable, "kern.py", how], cwd=pkg, env=env, check=True,
                             capture_output=True, text=True).stdout
        return int(out.split()[-1])

    assert run(1, "unguarded") == 1
    assert not (pkg / "__pycache__").exists() or not list((pkg / "__pycache__").glob("*.nbi"))
    # numba alone keys kern.kernel by kern.py, unchanged: the old helper's value comes back
    assert run(2, "unguarded") == 1
    # the guard (in the folder numba uses: under NUMBA_CACHE_DIR) drops it
    assert run(3, "guarded") == 3
    folder, = (tmp_path / "numba").glob("pkg_*")
    assert (folder / stale_cache.STAMP).exists()
    cached = {p: p.stat().st_mtime_ns for p in folder.glob("kern.kernel-*.nb*")}
    assert len(cached) == 2
    assert run(3, "guarded") == 3   # a cache that is current is loaded, not written again
    assert {p: p.stat().st_mtime_ns for p in folder.glob("kern.kernel-*.nb*")} == cached
    assert run(4, "guarded") == 4
