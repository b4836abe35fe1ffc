"""docs/limits.md and the code cannot drift apart: every value the table states is the code's,
and every limit in the code (a module-level MAX_* constant, what a check_count call counts
against, every check_memory call) has its row."""
import ast
import importlib
import inspect
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
PACKAGES = ("nlbeam", "continuation", "stochastic")
#: MAX_* constants that bound no work (with why)
NOT_LIMITS = {"nlbeam.summary.MAX_TEXT": "the width of a value in a printed summary"}
REF = re.compile(r"`((?:nlbeam|continuation|stochastic)\.[A-Za-z0-9_.]+(?:\([a-z_]+\))?)`")


def _rows():
    """(value text, [checked references]) of every table row of docs/limits.md."""
    out = []
    for line in (ROOT / "docs" / "limits.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 5 or cells[0] in ("limit", "---"):
            continue
        out.append((cells[1], REF.findall(cells[2])))
    return out


def _resolve(ref):
    """The object a dotted reference names (the longest importable module, then attributes)."""
    parts = ref.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for p in parts[i:]:
            obj = getattr(obj, p)
        return obj
    raise ImportError(ref)


def _value(text):
    m = re.fullmatch(r"`([0-9_ .*]+)`.*", text)
    return eval(m.group(1), {"__builtins__": {}}) if m else None


def _table_refs():
    return {r for _, refs in _rows() for r in refs}


def test_every_value_in_the_table_is_the_codes():
    checked = 0
    for text, refs in _rows():
        value = _value(text)
        assert refs, f"a row of docs/limits.md names no code: {text}"
        for ref in refs:
            m = re.fullmatch(r"(.+)\(([a-z_]+)\)", ref)
            if m:  # a default of a parameter
                default = inspect.signature(_resolve(m.group(1))).parameters[m.group(2)].default
                assert default == value, f"{ref}: the code says {default}, the table {value}"
                checked += 1
            elif value is not None and not callable(_resolve(ref)):
                assert _resolve(ref) == value, f"{ref}: the code says {_resolve(ref)}, " \
                                               f"the table {value}"
                checked += 1
            else:
                assert callable(_resolve(ref)), ref
    assert checked >= 15


def test_the_memory_budget_is_the_stated_share_of_the_available_memory(monkeypatch):
    from nlbeam import _validate

    share = [_value(t) for t, refs in _rows() if "nlbeam._validate.memory_budget" in refs][0]
    monkeypatch.delenv(_validate.MEMORY_ENV, raising=False)
    monkeypatch.setattr(_validate, "_available_memory", lambda: 8e9)
    assert _validate.memory_budget() == share * 8e9
    monkeypatch.setenv(_validate.MEMORY_ENV, "1e6")
    with pytest.raises(_validate.BudgetError, match="NLBEAM_MEMORY_BUDGET"):
        _validate.check_memory("a test", 2e6, "ask for less")


class _Walker(ast.NodeVisitor):
    """Module-level MAX_* constants, the names check_count counts against, the functions
    that call check_memory, and every function's parameter defaults, of one module."""

    def __init__(self, module):
        self.module, self.stack = module, []
        self.constants, self.count_names, self.memory_sites, self.defaults = [], set(), [], []

    def visit_ClassDef(self, node):
        self.stack.append(node.name)
        self.generic_visit(node)
        self.stack.pop()

    def visit_FunctionDef(self, node):
        self.stack.append(node.name)
        qual = ".".join([self.module] + self.stack)
        a = node.args
        pos = a.posonlyargs + a.args
        pairs = list(zip(pos[len(pos) - len(a.defaults):], a.defaults))
        pairs += [(k, d) for k, d in zip(a.kwonlyargs, a.kw_defaults) if d is not None]
        self.defaults += [(qual, arg.arg) for arg, _ in pairs]
        self.generic_visit(node)
        self.stack.pop()

    def visit_Call(self, node):
        name = getattr(node.func, "id", None)
        if name == "check_memory":
            self.memory_sites.append(".".join([self.module] + self.stack))
        if name == "check_count":
            limit = node.args[2] if len(node.args) > 2 else node.keywords[0].value
            self.count_names |= {n.id for n in ast.walk(limit) if isinstance(n, ast.Name)}
        self.generic_visit(node)


def _walk():
    walkers = []
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(f.relative_to(ROOT).with_suffix("").parts)
            module = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            tree = ast.parse(f.read_text())
            w = _Walker(module)
            w.visit(tree)
            for node in tree.body:
                if isinstance(node, ast.Assign):
                    w.constants += [f"{module}.{t.id}" for t in node.targets
                                    if isinstance(t, ast.Name) and re.match(r"_?MAX_", t.id)]
            walkers.append(w)
    return walkers


def test_every_limit_in_the_code_has_its_row():
    refs = _table_refs()
    walkers = _walk()
    missing = []
    params = set()
    for w in walkers:
        missing += [c for c in w.constants if c not in refs and c not in NOT_LIMITS]
        missing += [s for s in w.memory_sites if s not in refs]
        params |= w.count_names
    assert len([s for w in walkers for s in w.memory_sites]) >= 4
    for w in walkers:
        for name in w.count_names:
            if name.isupper() and f"{w.module}.{name}" not in refs:
                missing.append(f"{w.module}.{name}")
        for qual, arg in w.defaults:  # every default of what check_count counts against
            if arg in params and f"{qual}({arg})" not in refs:
                missing.append(f"{qual}({arg})")
    assert "max_steps" in params and "max_samples" in params
    assert not missing, f"limits in the code without a row in docs/limits.md: {missing}"
