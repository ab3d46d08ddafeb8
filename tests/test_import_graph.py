"""The package's import graph, read from the source (ast, nothing is imported).

Every import counts as an edge: at module level, inside a function (run later, but it still ties
the two modules together) and under ``if TYPE_CHECKING:`` (read by the type checker). An import
cycle means two modules that cannot be understood, tested or moved apart, so there must be none.
The command line (``toolimit.cli``) is the top of the graph: only itself, ``python -m toolimit``
and the tests may import it.
"""

from __future__ import annotations

import ast
import json
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = "toolimit"


def module_files(root: Path, package: str) -> dict[str, Path]:
    """Module name -> file of every module of ``package`` (a folder of ``root``); a package's
    ``__init__.py`` is the module named after its folder."""
    modules = {}
    for path in sorted((root / package).rglob("*.py")):
        parts = path.relative_to(root).with_suffix("").parts
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def imported_names(tree: ast.AST, module: str, is_package: bool) -> list[str]:
    """Every dotted name ``tree`` imports, wherever the import stands, relative ones made absolute:
    ``import a.b`` gives ``a.b``; ``from a import b, c`` gives ``a.b`` and ``a.c`` (modules or not,
    :func:`import_graph` tells)."""
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.extend(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = module.split(".") if is_package else module.split(".")[:-1]
                parts = parts[: len(parts) - (node.level - 1)]
                base = ".".join(parts + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            names.extend(f"{base}.{alias.name}" for alias in node.names)
    return names


def import_graph(root: Path, package: str) -> dict[str, set[str]]:
    """Module -> the modules of ``package`` it imports. ``from X import Y`` is an edge to ``X.Y``
    when that is a module of the package, else to ``X``; ValueError for an import of the package
    that names no module of it (a resolution this test got wrong, or a broken import)."""
    modules = module_files(root, package)
    graph: dict[str, set[str]] = {}
    for module, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        edges = set()
        for name in imported_names(tree, module, path.name == "__init__.py"):
            if name.split(".")[0] != package:
                continue
            target = name if name in modules else name.rpartition(".")[0]
            if target not in modules:
                raise ValueError(f"{path}: imports {name}, which is no module of {package}")
            if target != module:
                edges.add(target)
        graph[module] = edges
    return graph


def import_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as [a, b, ..., a], or None when it has none."""
    try:
        TopologicalSorter(graph).prepare()
    except CycleError as error:
        return list(error.args[1])
    return None


def test_the_package_has_no_import_cycle():
    graph = import_graph(REPO, PACKAGE)
    assert len(graph) == len(list((REPO / PACKAGE).rglob("*.py"))) and sum(map(len, graph.values())) > 300
    cycle = import_cycle(graph)
    assert cycle is None, f"import cycle: {' -> '.join(reversed(cycle))}"


def test_the_graph_builder_finds_a_cycle_through_every_kind_of_import(tmp_path):
    files = {
        "pkg/__init__.py": "from pkg.a import A\n",
        "pkg/a.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.sub import b\nA = 1\n",
        "pkg/sub/__init__.py": "",
        "pkg/sub/b.py": "def f():\n    from ..c import C\n    return C\n",
        "pkg/c.py": "import os\nfrom . import a\nC = 2\n",
        "pkg/d.py": "import pkg.sub\nfrom pkg import c\n",
    }
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    graph = import_graph(tmp_path, "pkg")
    assert graph == {
        "pkg": {"pkg.a"},
        "pkg.a": {"pkg.sub.b"},
        "pkg.sub": set(),
        "pkg.sub.b": {"pkg.c"},
        "pkg.c": {"pkg.a"},
        "pkg.d": {"pkg.sub", "pkg.c"},
    }
    cycle = import_cycle(graph)
    assert cycle is not None and set(cycle) == {"pkg.a", "pkg.sub.b", "pkg.c"}
    graph["pkg.c"].clear()
    assert import_cycle(graph) is None


def test_an_import_of_no_module_is_an_error(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("from pkg.missing import X\n")
    with pytest.raises(ValueError, match="imports pkg.missing.X, which is no module of pkg"):
        import_graph(tmp_path, "pkg")


# --- who may import the command line -----------------------------------------------------------
CLI = f"{PACKAGE}.cli"
#: Where importing the command line is expected: itself, ``python -m toolimit`` and the tests.
CLI_IMPORTERS = ("toolimit/cli/", "toolimit/__main__.py", "tests/")
#: Where code that must not import it lives.
SCANNED = ("toolimit", "scripts", "benchmarks", "course")


def notebook_code(path: Path) -> str:
    """The code cells of a notebook as one Python text, IPython's ``%`` and ``!`` lines left out."""
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    lines = []
    for cell in cells:
        if cell["cell_type"] == "code":
            source = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
            lines += [line for line in source.splitlines() if not line.lstrip().startswith(("%", "!"))]
    return "\n".join(lines)


def imports_cli(text: str, path: Path) -> list[str]:
    """The names of ``toolimit.cli`` that the code ``text`` (of the file ``path``) imports."""
    relative = path.relative_to(REPO)
    module = ".".join(relative.with_suffix("").parts)
    is_package = path.name == "__init__.py"
    tree = ast.parse(text, filename=str(path))
    return [name for name in imported_names(tree, module, is_package) if name == CLI or name.startswith(f"{CLI}.")]


def test_only_the_command_line_and_the_tests_import_the_command_line():
    files = [path for folder in SCANNED for path in sorted((REPO / folder).rglob("*.py"))]
    files += sorted((REPO / "notebooks").glob("*.ipynb"))
    assert len(files) > 100
    offenders = []
    for path in files:
        relative = path.relative_to(REPO).as_posix()
        if relative.startswith(CLI_IMPORTERS):
            continue
        text = notebook_code(path) if path.suffix == ".ipynb" else path.read_text(encoding="utf-8")
        names = imports_cli(text, path)
        if names:
            offenders.append(f"{relative}: {', '.join(sorted(set(names)))}")
    assert not offenders, "the command line is imported by a library module, script or notebook:\n" + "\n".join(
        offenders
    )


# --- who may import Ray ------------------------------------------------------------------------
#: The one module that imports Ray (the optional extra ``toolimit[ray]``).
RAY_IMPORTER = "toolimit/distributed.py"


def test_only_the_distributed_module_imports_ray():
    importers = []
    for path in sorted((REPO / PACKAGE).rglob("*.py")):
        relative = path.relative_to(REPO)
        module = ".".join(relative.with_suffix("").parts)
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        names = imported_names(tree, module, path.name == "__init__.py")
        if any(name == "ray" or name.startswith("ray.") for name in names):
            importers.append(relative.as_posix())
    assert importers == [RAY_IMPORTER]
