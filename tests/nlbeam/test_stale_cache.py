"""numba's kernel caches are dropped when any kernel source changes (numba itself keys a cache by
the defining file only, so a kernel that inlines an edited function would run the old code)."""
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
    stamp = here / "__pycache__" / stale_cache.STAMP
    if not stamp.exists():  # a read-only install: nothing to check
        return
    import sys

    import numba
    digest = stale_cache.sources_digest(sorted(here.glob("*.py")),
                                        extra=(sys.version, numba.__version__))
    assert stamp.read_text().strip() == digest
