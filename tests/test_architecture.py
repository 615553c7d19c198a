"""The house's rules, read from the code (docs/architecture.md): no private name crosses a
package, at most one import circle (named), four doors to the compiled core, no file above 700
lines and no function above 120.

Python rules first; the Rust core's follow in their own section."""

import ast
import importlib
import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "python" / "vtb"

# ------------------------------------------------------------------------------------ Python

#: The modules that may import the compiled core, one per side of it: the configuration's
#: checks and library, the runs, the assembled structure and its modes, the signal kernels.
CORE_DOORS = {"vtb.config.gateway", "vtb.run.simulate", "vtb.analysis.eigen", "vtb.analysis.spectra"}
#: The one import circle allowed, and why: a configuration's own check (Config.validate) is that
#: of a prepared run, and the preparation takes a Config (prepare → resolution → fields).
ALLOWED_CIRCLE = {"vtb.config.fields", "vtb.config.prepare", "vtb.config.resolution"}
MAX_LINES = 700
MAX_FUNCTION_LINES = 120


def _name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict:
    return {_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


MODULES = _modules()


def _imports(name: str, path: Path):
    """(target module, imported name or None) of every import of ``name``, at the top or inside
    a function alike (the ones inside functions are how circles hide)."""
    is_package = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name, None
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_package else name.split(".")[:-1]
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for a in node.names:
                yield target, a.name


def _edges() -> dict:
    """module → the vtb modules it imports (``from pkg import module`` counts as that module)."""
    edges = {}
    for name, path in MODULES.items():
        out = set()
        for target, item in _imports(name, path):
            full = f"{target}.{item}" if item else target
            if full == "vtb._core":  # the compiled core, not a module of this tree
                continue
            if full in MODULES:
                out.add(full)
            elif target in MODULES:
                out.add(target)
        edges[name] = out - {name}
    return edges


def _circles(edges: dict) -> list:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(comp)

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def _package(module: str) -> str:
    """The subpackage a module belongs to (``vtb.run`` for ``vtb.run.simulate``; ``vtb`` for top-level modules)."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 and (PACKAGE / parts[1]).is_dir() else "vtb"


def test_no_private_name_is_imported_across_packages():
    crossings = []
    for name, path in MODULES.items():
        for target, item in _imports(name, path):
            if not (target and target.startswith("vtb") and item and item.startswith("_")) or item in ("__version__", "_core"):
                continue
            if f"{target}.{item}" in MODULES:  # a private module of the package, e.g. vtb._moved
                continue
            if _package(target) != _package(name):
                crossings.append(f"{name} imports {item} from {target}")
    assert not crossings, "private names crossing packages (make them public where they live, or move the code): " + "; ".join(crossings)


def test_at_most_one_import_circle_and_it_is_the_named_one():
    circles = _circles(_edges())
    assert len(circles) <= 1, f"{len(circles)} import circles: " + "; ".join(" ↔ ".join(sorted(c)) for c in circles)
    for c in circles:
        assert c == ALLOWED_CIRCLE, (f"an import circle other than the named one ({', '.join(sorted(ALLOWED_CIRCLE))}): "
                                     f"{', '.join(sorted(c))}")


def test_the_circle_detector_sees_imports_inside_functions():
    edges = {"a": {"b"}, "b": {"a"}, "c": {"a"}}
    assert _circles(edges) == [{"a", "b"}]
    # vtb.config.fields reaches vtb.config.prepare only inside Config.validate
    assert "vtb.config.prepare" in _edges()["vtb.config.fields"]


def test_at_most_four_modules_import_the_core():
    doors = {name for name, path in MODULES.items() for target, item in _imports(name, path)
             if target == "vtb._core" or (target == "vtb" and item == "_core")}
    assert len(doors) <= 4, f"{len(doors)} modules import vtb._core (at most 4): {', '.join(sorted(doors))}"
    assert doors <= CORE_DOORS, f"modules other than the doors {sorted(CORE_DOORS)} import vtb._core: {', '.join(sorted(doors - CORE_DOORS))}"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_file_above_700_lines_and_no_function_above_120(name):
    path = MODULES[name]
    text = path.read_text()
    lines = len(text.splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(ROOT)} has {lines} lines (at most {MAX_LINES}): split it by purpose"
    long = [f"{n.name} ({n.end_lineno - n.lineno + 1} lines, from line {n.lineno})" for n in ast.walk(ast.parse(text))
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.end_lineno - n.lineno + 1 > MAX_FUNCTION_LINES]
    assert not long, f"{path.relative_to(ROOT)}: functions above {MAX_FUNCTION_LINES} lines: {', '.join(long)}"


def test_old_module_paths_warn_and_are_the_new_modules():
    """Each former flat module is its new module under the old name, after a DeprecationWarning
    naming the new path; ``import vtb`` itself warns of nothing and keeps its functions."""
    import vtb

    shims = sorted(p.stem for p in PACKAGE.glob("*.py") if "_moved import moved" in p.read_text())
    assert len(shims) >= 25, shims
    for old in shims:
        sys.modules.pop(f"vtb.{old}", None)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            module = importlib.import_module(f"vtb.{old}")
        new = module.__name__
        assert new != f"vtb.{old}" and sys.modules[f"vtb.{old}"] is sys.modules[new], old
        assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message) for w in caught), old
    assert callable(vtb.simulate) and callable(vtb.optimize) and callable(vtb.spans) and callable(vtb.trains)
    quiet = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c", "import vtb, vtb.cli"], capture_output=True, text=True,
                           env={**os.environ, "PYTHONPATH": str(Path(vtb.__file__).resolve().parent.parent)})
    assert quiet.returncode == 0, quiet.stderr


# -------------------------------------------------------------------------------------- Rust

RUST = ROOT / "rust" / "src"
#: The core's trades from the ground up: each may import only those below it (docs/architecture.md).
#: `error` is everyone's; `config` and `linalg` stand on it alone; `library` builds
#: configurations.
TRADES = {
    "error": 0,
    "config": 1,
    "linalg": 1,
    "library": 2,
    "model": 2,
    "outputs": 3,
    "check": 4,
    "engine": 5,
}


def _rust_files():
    return sorted(p for p in RUST.rglob("*.rs") if p.name not in ("lib.rs", "tests.rs"))


def _trade(path: Path) -> str:
    return path.relative_to(RUST).parts[0].removesuffix(".rs")


def _code(path: Path) -> str:
    """The file without its test module and comments (tests may use any trade)."""
    text = path.read_text()
    cut = text.find("#[cfg(test)]")
    return "\n".join(line.split("//")[0] for line in (text[:cut] if cut >= 0 else text).splitlines())


def _rust_imports():
    """(file, its trade, the trade it names) of every `crate::trade` path outside tests."""
    import re

    for p in _rust_files():
        for used in set(re.findall(r"crate::([a-z_]+)", _code(p))):
            yield p, _trade(p), used


def test_every_rust_file_belongs_to_a_trade():
    assert {_trade(p) for p in _rust_files()} <= set(TRADES), sorted({_trade(p) for p in _rust_files()} - set(TRADES))


def test_no_core_folder_imports_one_above_it():
    """No upward import between the core's folders (an import within a folder is its own
    business; the `wide` macro of linalg is exported at the crate's root)."""
    upward = sorted(f"{p.relative_to(ROOT)}: {trade} -> {used}" for p, trade, used in _rust_imports()
                    if used in TRADES and used != trade and TRADES[used] >= TRADES[trade])
    assert not upward, "imports that run up or sideways:\n" + "\n".join(upward)


def test_the_rust_rule_sees_an_upward_import(tmp_path):
    """The detector on a made-up file: config naming the engine is found."""
    import re

    text = "use crate::engine::MAX_LANES;\n#[cfg(test)]\nmod tests { use crate::library::presets; }\n"
    names = set(re.findall(r"crate::([a-z_]+)", text[: text.find("#[cfg(test)]")]))
    assert names == {"engine"} and TRADES["engine"] > TRADES["config"]


def _rust_functions(path: Path):
    """(name, lines) of every function with a body, outside the test module."""
    import re

    lines = _code(path).splitlines()
    head = re.compile(r"^(\s*)(pub(\([a-z]+\))? )?(const )?(unsafe )?fn (\w+)")
    for i, line in enumerate(lines):
        m = head.match(line)
        if not m:
            continue
        k = i
        while not lines[k].rstrip().endswith(("{", ";")):
            k += 1
        if lines[k].rstrip().endswith(";"):
            continue  # a declaration
        end = next(j for j in range(k + 1, len(lines)) if lines[j] == m.group(1) + "}")
        yield m.group(6), end - i + 1


@pytest.mark.parametrize("path", _rust_files(), ids=lambda p: str(p.relative_to(RUST)))
def test_no_rust_file_above_700_lines_and_no_function_above_120(path):
    assert len(_code(path).splitlines()) <= MAX_LINES
    long = [(n, k) for n, k in _rust_functions(path) if k > MAX_FUNCTION_LINES]
    assert not long, long


def test_the_docs_name_files_that_exist():
    """Every source path a doc names (rust/src/…, python/vtb/…, tests/…, benches/….py) exists:
    the docs follow the code when it moves."""
    import re

    docs = sorted((ROOT / "docs").glob("*.md")) + [p for p in (ROOT / "README.md", ROOT / "CONTRIBUTING.md") if p.exists()]
    missing = []
    for d in docs:
        for m in re.finditer(r"(rust/src/[\w/.]+|python/vtb/[\w/.]+|tests/[\w/]+\.py|benches/[\w/]+\.(?:py|rs))", d.read_text()):
            path = m.group(1).rstrip(".")
            if "new_model" not in path and not (ROOT / path).exists():
                missing.append(f"{d.name}: {path}")
    assert not missing, missing
