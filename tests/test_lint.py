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


MAX_LINE = 100   # characters


def long_lines(root):
    """(path:line, length) of every .py line under the project's folders longer than MAX_LINE."""
    found = []
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
                if len(line) > MAX_LINE:
                    found.append((f"{path.relative_to(root)}:{i}", len(line)))
    return found


def test_no_line_is_longer_than_the_limit():
    assert long_lines(ROOT) == []


def test_the_line_check_sees_a_long_line(tmp_path):
    (tmp_path / "nlbeam").mkdir()
    (tmp_path / "nlbeam" / "m.py").write_text("x = 1\n" + "y = '" + "a" * 100 + "'\n")
    assert long_lines(tmp_path) == [("nlbeam/m.py:2", 106)]
