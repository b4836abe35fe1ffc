"""The code is pyflakes-clean (unused imports and names, undefined names, f-strings without
placeholders): the README's test command lints too, as .ci/run does before it."""
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
FOLDERS = ("nlbeam", "continuation", "stochastic", "tests", "benchmarks", "figures")


def test_pyflakes_finds_nothing():
    api = pytest.importorskip("pyflakes.api", reason="pip install -e '.[test]' brings pyflakes")
    from pyflakes.reporter import Reporter
    import io

    out, err = io.StringIO(), io.StringIO()
    n = sum(api.checkRecursive([str(ROOT / f)], Reporter(out, err)) for f in FOLDERS)
    assert n == 0, out.getvalue() + err.getvalue()


def test_the_lint_sees_an_unused_import(tmp_path):
    api = pytest.importorskip("pyflakes.api")
    from pyflakes.reporter import Reporter
    import io

    bad = tmp_path / "bad.py"
    bad.write_text("import os\n")
    out = io.StringIO()
    assert api.checkRecursive([str(bad)], Reporter(out, io.StringIO())) == 1
    assert "'os' imported but unused" in out.getvalue()
