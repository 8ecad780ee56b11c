"""The house rules of docs/ARCHITECTURE.md as tests.

Each rule is a function from a source tree to its violations, one line each naming the file and
the rule; the tests run every rule on this checkout (no violation) and on a small tree with one
violation planted (caught, and named).  The rules read the files as text (ast), import nothing.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# The floors of the house, top to bottom (docs/ARCHITECTURE.md): an import may run to a lower
# floor, or stay inside its own wing; never up, never across to another wing of the same floor.
# Longest prefix wins.  A module that no row names fails `test_every_module_has_a_floor`.
FLOORS = {
    "shadowvol.cli": (9, "cli"),
    "shadowvol.batch": (8, "batch"),
    "shadowvol.view": (7, "view"),
    "shadowvol.course": (6, "course"),
    "shadowvol.compare": (5, "compare"),
    "shadowvol.raster": (4, "raster"),
    # the raster wing's families, one folder each (raw GL and ctypes allowed in all: CONFINED)
    "shadowvol.raster.platform": (4, "raster"),
    "shadowvol.raster.volumes": (4, "raster"),
    "shadowvol.raster.truth": (4, "raster"),
    "shadowvol.raster.overflow": (4, "raster"),
    "shadowvol.raster.planar": (4, "raster"),
    "raytrace": (4, "raytrace"),
    "shadowvol.scenefile": (3, "model"),
    "shadowvol.scenefile_mesh": (3, "model"),
    "shadowvol.scenefile_gltf": (3, "model"),
    "shadowvol.scenefile_texture": (3, "model"),
    "shadowvol.scenefile_write": (3, "model"),
    "shadowvol.trimesh_scene": (3, "model"),
    "shadowvol.resources": (3, "model"),
    "shadowvol.memory": (3, "model"),
    "shadowvol.scene": (2, "model"),
    "shadowvol.lights": (2, "model"),
    "shadowvol.cameras": (2, "model"),
    "shadowvol.primitives": (2, "model"),
    "shadowvol.arealights": (2, "model"),
    "shadowvol.frame": (2, "model"),
    "shadowvol.planes": (2, "model"),
    "shadowvol.checks": (2, "model"),
    "shadowvol.textures": (2, "model"),
    "shadowvol.io": (1, "base"),
    "shadowvol.pictures": (1, "base"),
    "shadowvol.display": (1, "base"),
    "shadowvol.errors": (0, "base"),
    "shadowvol.signals": (0, "base"),
    "shadowvol": (0, "base"),
}
# Entry files: `python -m shadowvol` and `python -m raytrace` start the command line.
ENTRY_FILES = {"shadowvol.__main__", "raytrace.__main__"}
# What the witness may import of this project: the model it shares with the rasterizer (and
# `memory`, the GL-free vocabulary each renderer gives its own memory estimate in).
RAYTRACE_MAY_IMPORT = {"shadowvol", "shadowvol.scene", "shadowvol.lights", "shadowvol.cameras",
                       "shadowvol.primitives", "shadowvol.arealights", "shadowvol.frame",
                       "shadowvol.planes", "shadowvol.checks", "shadowvol.errors", "shadowvol.io",
                       "shadowvol.signals", "shadowvol.memory",
                       "shadowvol.textures"}
# Global illumination, beyond the witness: the rest of raytrace/ (the witness: masks, groundtruth,
# soft, backends, intersect, tolerances, camera) never imports it; the package's door
# (`raytrace/__init__.py`, which names `raytrace.render` lazily) may.
OUTLOOK = "raytrace.outlook"
WITNESS_DOOR = {"raytrace"}
# Third-party and standard modules that only one folder (or file) may import.  ctypes: the raw
# GL bindings in shadowvol/raster, and the one raw-Embree file of the witness (which may not
# import the raster): raytrace/embree4.py binds the packet queries of the Embree library the
# embreex wheel ships (issue "Rays at full speed"); no other witness module may.
CONFINED = {"moderngl": ("shadowvol/raster/",), "glcontext": ("shadowvol/raster/",),
            "OpenGL": ("shadowvol/raster/",),
            "ctypes": ("shadowvol/raster/", "raytrace/embree4.py"),
            "argparse": ("shadowvol/cli/",)}
PRODUCT = ("shadowvol", "raytrace")
SIZED = ("shadowvol", "raytrace", "benchmarks")
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80
MAX_README_LINES = 200
MAX_BENCHMARKS_LINES = 450
# The docs whose paths must exist; docstrings and comments of every module are read too.
DOCS = ("README.md", "BENCHMARKS.md", "docs/*.md", "docs/benchmarks/*.md", "docs/*.ipynb",
        "scenes/README.md", "benchmarks/*.md")
TOP_DIRS = {"shadowvol", "raytrace", "shaders", "scenes", "tests", "docs", "benchmarks", ".ci"}


# ---------------------------------------------------------------------------------------------
# Reading the tree
# ---------------------------------------------------------------------------------------------

def modules(root: Path, tops=PRODUCT) -> dict[str, Path]:
    """Dotted name -> file of every module under the `tops` folders of `root`."""
    out = {}
    for top in tops:
        for path in sorted((root / top).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


def _from_module(name: str, path: Path, node: ast.ImportFrom) -> str:
    """The module a `from ... import` of the module `name` (file `path`) reads, resolved."""
    if not node.level:
        return node.module
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    base = package.split(".")[: len(package.split(".")) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(name: str, path: Path, known) -> list[tuple[str, int]]:
    """(imported module, line) for every import in the file, function-level ones too.
    `from P import x` names P.x where that is a module, else P; relative imports resolved."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = _from_module(name, path, node)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.append((sub if sub in known else target, node.lineno))
    return list(dict.fromkeys(out))


def floor_of(module: str):
    """(floor, wing) of one of this project's modules, or None when no row names it."""
    best = max((prefix for prefix in FLOORS if module == prefix
                or (prefix != "shadowvol" and module.startswith(prefix + "."))),
               key=len, default=None)
    return FLOORS[best] if best is not None else None


def _ours(module: str) -> bool:
    return module.split(".")[0] in PRODUCT


def _rel(root: Path, path: Path) -> str:
    return path.relative_to(root).as_posix()


# ---------------------------------------------------------------------------------------------
# The rules: each returns its violations, one line each
# ---------------------------------------------------------------------------------------------

def unplaced_modules(root: Path) -> list[str]:
    return [f"{_rel(root, path)}: module {name} has no floor in FLOORS (tests/"
            f"test_architecture.py): give it one" for name, path in modules(root).items()
            if floor_of(name) is None and name not in ENTRY_FILES]


def upward_imports(root: Path) -> list[str]:
    found = modules(root)
    out = []
    for name, path in found.items():
        here = floor_of(name)
        if name in ENTRY_FILES or here is None:
            continue
        for target, line in imports_of(name, path, found):
            there = floor_of(target) if _ours(target) else None
            if there is None or there[1] == here[1] or there[0] < here[0]:
                continue
            way = "up" if there[0] > here[0] else "across"
            out.append(f"{_rel(root, path)}:{line}: imports {target} ({there[1]}, floor "
                       f"{there[0]}) from {here[1]} (floor {here[0]}): an import runs {way}")
    return out


def import_cycles(root: Path) -> list[str]:
    """Strongly connected components of the module graph (Tarjan), each named once."""
    found = modules(root)
    graph = {name: sorted({t for t, _ in imports_of(name, path, found) if t in found} - {name})
             for name, path in found.items()}
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return [f"{_rel(root, found[c[0]])}: import cycle {' <-> '.join(c)}" for c in cycles]


def confined_imports(root: Path) -> list[str]:
    found = modules(root)
    out = []
    for name, path in found.items():
        rel = _rel(root, path)
        for target, line in imports_of(name, path, found):
            homes = CONFINED.get(target.split(".")[0])
            if homes is not None and not any(rel == h or (h.endswith("/") and rel.startswith(h))
                                             for h in homes):
                out.append(f"{rel}:{line}: imports {target}, which only "
                           f"{' and '.join(homes)} may import")
    return out


def witness_imports(root: Path) -> list[str]:
    found = modules(root)
    out = []
    for name, path in found.items():
        if not name.startswith("raytrace") or name in ENTRY_FILES:
            continue
        for target, line in imports_of(name, path, found):
            if target.startswith("shadowvol") and target not in RAYTRACE_MAY_IMPORT:
                out.append(f"{_rel(root, path)}:{line}: the witness imports {target}; raytrace/"
                           f" may import only the model ({', '.join(sorted(RAYTRACE_MAY_IMPORT))})")
    return out


def witness_apart(root: Path) -> list[str]:
    found = modules(root)
    out = []
    for name, path in found.items():
        if (not name.startswith("raytrace") or name == OUTLOOK or name.startswith(OUTLOOK + ".")
                or name in ENTRY_FILES | WITNESS_DOOR):
            continue
        for target, line in imports_of(name, path, found):
            if target == OUTLOOK or target.startswith(OUTLOOK + "."):
                out.append(f"{_rel(root, path)}:{line}: the witness imports {target}; "
                           f"{OUTLOOK.replace('.', '/')}/ (global illumination) may import the "
                           "witness, never the reverse")
    return out


def renamed_imports(root: Path) -> list[str]:
    """A module of ours imported under another name (`from shadowvol.cli import args as
    blocks`, `import raytrace.masks as rm`): each module is called by its own name everywhere."""
    found = modules(root, SIZED)
    out = []
    for name, path in found.items():
        rel = _rel(root, path)
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                renamed = [(a.name, a.asname) for a in node.names
                           if a.asname and a.asname != a.name.rpartition(".")[2]]
            elif isinstance(node, ast.ImportFrom):
                target = _from_module(name, path, node)
                renamed = [(f"{target}.{a.name}", a.asname) for a in node.names
                           if a.asname and a.asname != a.name]
            else:
                continue
            out += [f"{rel}:{node.lineno}: imports the module {module} as {alias}: call a "
                    "module of ours by its own name" for module, alias in renamed
                    if module in found]
    return out


def oversized(root: Path) -> list[str]:
    out = []
    for path in modules(root, SIZED).values():
        text = path.read_text()
        rel = _rel(root, path)
        lines = len(text.splitlines())
        if lines > MAX_MODULE_LINES:
            out.append(f"{rel}: {lines} lines, over the cap of {MAX_MODULE_LINES} a module")
        for node in ast.walk(ast.parse(text, str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = node.end_lineno - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    out.append(f"{rel}:{node.lineno}: function {node.name} is {length} lines, "
                               f"over the cap of {MAX_FUNCTION_LINES} a function")
    return out


def long_docs(root: Path) -> list[str]:
    out = []
    for name, cap in (("README.md", MAX_README_LINES), ("BENCHMARKS.md", MAX_BENCHMARKS_LINES)):
        path = root / name
        if path.exists() and len(path.read_text().splitlines()) > cap:
            out.append(f"{name}: {len(path.read_text().splitlines())} lines, over its cap of "
                       f"{cap}")
    return out


# A repository path: a top folder (or a shadowvol/ wing) then /-separated names, ending in a
# file with an extension or a slash.  Globs, placeholders and URLs are not paths.
_PATH = re.compile(r"(?<![\w./:-])((?:\.ci|[a-z_]+)/(?:[\w.-]+/)*[\w-]+(?:\.[a-z0-9]+)+|"
                   r"(?:\.ci|[a-z_]+)/(?:[\w.-]+/)+)(?![\w*{<])")
_DOTTED = re.compile(r"(?<![\w./-])((?:shadowvol|raytrace)(?:\.[A-Za-z_]\w*)+)")
_RUN_MODULE = re.compile(r"python3? -m ([\w.]+)")


def _texts(root: Path):
    """(file, line, text) of every doc line, and of every docstring and comment of the
    product's and the benchmarks' modules."""
    for pattern in DOCS:
        for path in sorted(root.glob(pattern)):
            for i, line in enumerate(path.read_text().splitlines(), 1):
                yield path, i, line
    for path in modules(root, SIZED).values():
        source = path.read_text()
        for node in ast.walk(ast.parse(source, str(path))):
            body = getattr(node, "body", None)
            if (isinstance(body, list) and body and isinstance(body[0], ast.Expr)
                    and isinstance(body[0].value, ast.Constant)
                    and isinstance(body[0].value.value, str)):
                for i, line in enumerate(body[0].value.value.splitlines()):
                    yield path, body[0].lineno + i, line
        for i, line in enumerate(source.splitlines(), 1):
            if "#" in line:
                yield path, i, line[line.index("#"):]


def _names_of(path: Path) -> set[str]:
    """The top-level names a module defines or imports (what `module.name` can mean)."""
    names = set()
    for node in ast.parse(path.read_text(), str(path)).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
                if isinstance(target, ast.Name) and target.id == "_LAZY":
                    names |= {k.value for k in ast.walk(node.value)
                              if isinstance(k, ast.Constant) and isinstance(k.value, str)}
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return names


# Packages the wheel maps from other folders (pyproject.toml's package-dir).
PACKAGE_DIRS = {"shadowvol.shaders": "shaders", "shadowvol.scenes": "scenes"}


def _dotted_exists(root: Path, dotted: str) -> bool:
    """Whether the module part of `a.b.c.name...` exists and its next name is defined there."""
    if any(dotted == p or dotted.startswith(p + ".") for p in PACKAGE_DIRS):
        package = next(p for p in PACKAGE_DIRS if dotted == p or dotted.startswith(p + "."))
        return (root / PACKAGE_DIRS[package]).is_dir()
    parts = dotted.split(".")
    here = root / parts[0]
    for i, part in enumerate(parts[1:], 1):
        if (here / part).is_dir() and (here / part / "__init__.py").exists():
            here = here / part
        elif (here / f"{part}.py").exists():
            return i + 1 == len(parts) or parts[i + 1] in _names_of(here / f"{part}.py") \
                or parts[i + 1] in {"py"}
        else:
            init = here / "__init__.py"
            return init.exists() and part in _names_of(init)
    return True


def _module_exists(root: Path, module: str) -> bool:
    path = root.joinpath(*module.split("."))
    return path.with_suffix(".py").exists() or (path / "__main__.py").exists()


def _path_exists(root: Path, source: Path, path: str) -> bool:
    path = path.rstrip("/")
    candidates = [root / path, source.parent / path, root / "shadowvol" / path]
    return any(c.exists() for c in candidates)


def broken_references(root: Path) -> list[str]:
    out = []
    for source, line, text in _texts(root):
        rel = _rel(root, source)
        for match in _PATH.finditer(text):
            path = match.group(1)
            top = path.split("/")[0]
            wings = {p.name for p in (root / "shadowvol").iterdir() if p.is_dir()}
            if top not in TOP_DIRS | wings or _path_exists(root, source, path):
                continue
            out.append(f"{rel}:{line}: names {path}, which does not exist")
        for match in _DOTTED.finditer(text):
            dotted = match.group(1).rstrip(".")
            if not _dotted_exists(root, dotted):
                out.append(f"{rel}:{line}: names {dotted}, which does not exist")
        for match in _RUN_MODULE.finditer(text):
            module = match.group(1).rstrip(".")
            if module.split(".")[0] in TOP_DIRS and not _module_exists(root, module):
                out.append(f"{rel}:{line}: runs python -m {module}, which does not exist")
    return out


# The wings of tests/: a test file lives in the folder of what it tests, read from what it uses.
# Folder -> the product's modules it holds the tests of (longest prefix wins, as in FLOORS; the
# model and the base floors are one test wing, `scene`).  tests/system/ holds the whole-product
# tests, which use the product only as a user does: processes, or the packages' public API.
TEST_WINGS = {
    "cli": ("shadowvol.cli",), "batch": ("shadowvol.batch",), "view": ("shadowvol.view",),
    "course": ("shadowvol.course",), "compare": ("shadowvol.compare",),
    "raster": ("shadowvol.raster",), "raytrace": ("raytrace",),
    "raytrace/outlook": ("raytrace.outlook",), "scene": ("shadowvol",),
    "benchmarks": ("benchmarks",),
}
SYSTEM = "system"
# what `python -m shadowvol` / `python -m raytrace` (or an argv naming a tool) runs
COMMANDS = {"shadowvol": "shadowvol.cli", "raytrace": "shadowvol.cli"}
PACKAGES = {"shadowvol", "raytrace"}


def wing_of_module(module: str):
    """The folder of tests/ that holds the tests of one of the project's modules."""
    best = max(((prefix, folder) for folder, prefixes in TEST_WINGS.items() for prefix in prefixes
                if module == prefix or module.startswith(prefix + ".")),
               key=lambda row: len(row[0]), default=(None, None))
    return best[1]


def uses_of(path: Path, known) -> tuple[set[str], set[str]]:
    """(imported, used) modules of the project by a test file: `imported` its imports (function
    level too); `used` those, the modules a string names (`python -m benchmarks.run`), and the
    command line where a string names a tool (`python -m shadowvol`, an argv)."""
    imported, used = set(), set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            imported |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            imported |= {f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in known
                         else node.module for a in node.names}
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if node.value in COMMANDS:
                used.add(COMMANDS[node.value])
            elif "." in node.value and node.value in known:
                used.add(node.value)
    imported = {m for m in imported if m.split(".")[0] in SIZED}
    return imported, imported | used


def misplaced_tests(root: Path) -> list[str]:
    """Each tests/<wing>/test_*.py uses a module of its wing (the witness's tests, at the top of
    tests/raytrace/, none of raytrace/outlook/); each tests/system/ one imports nothing of the
    product but the packages themselves.  Shared helpers (tests/*.py) and conftest.py are free."""
    known = modules(root, SIZED)
    out = []
    for path in sorted((root / "tests").rglob("test_*.py")):
        folder = path.parent.relative_to(root / "tests").as_posix()
        if folder == ".":
            continue
        rel = _rel(root, path)
        imported, used = uses_of(path, known)
        if folder == SYSTEM:
            inside = sorted(imported - PACKAGES)
            if inside:
                out.append(f"{rel}: a whole-product test imports {', '.join(inside)}: it tests "
                           f"that module's wing ({wing_of_module(inside[0])}), or the product only "
                           "through processes and the packages")
            continue
        if folder not in TEST_WINGS:
            out.append(f"{rel}: tests/{folder}/ is no wing of tests/ (TEST_WINGS in tests/"
                       f"test_architecture.py)")
            continue
        wings = {wing_of_module(m) for m in used}
        if folder not in wings:
            named = ", ".join(sorted(w for w in wings if w)) or "nothing of the product"
            out.append(f"{rel}: uses nothing of its wing tests/{folder}/ (it uses: {named}): a "
                       "test lives in the wing of what it tests")
        elif folder == "raytrace" and "raytrace/outlook" in wings:
            outlook = sorted(m for m in used if wing_of_module(m) == "raytrace/outlook")
            out.append(f"{rel}: a test of the witness uses {', '.join(outlook)}: it is a test of "
                       "the outlook (tests/raytrace/outlook/)")
    return out


def _module_names(found) -> dict[str, list[str]]:
    """Module -> the words that name it: its dotted path, and each end of that path no other
    module shares (`raster.estimate`, `passes`), with / or . between the parts."""
    ends: dict[str, set[str]] = {}
    for name in found:
        parts = name.split(".")
        for i in range(len(parts)):
            ends.setdefault(".".join(parts[i:]), set()).add(name)
    out = {}
    for name in found:
        parts = name.split(".")
        own = [".".join(parts[i:]) for i in range(len(parts))
               if i == 0 or ends[".".join(parts[i:])] == {name}]
        out[name] = own + [o.replace(".", "/") for o in own]
    return out


def unnamed_modules(root: Path) -> list[str]:
    """Every module of the product is named in docs/ARCHITECTURE.md, as a whole word (not the end
    of a longer path): its dotted path or an end of it that no other module shares (`passes`,
    `raster/estimate`, `outlook.estimate`, a package as `outlook/`), with / or . between the
    parts; `python -m P` names P/__main__.py."""
    doc = root / "docs" / "ARCHITECTURE.md"
    text = doc.read_text() if doc.exists() else ""
    found = modules(root)
    out = []
    for name, words in _module_names(found).items():
        if found[name].name == "__main__.py":
            ok = f"python -m {name.rpartition('.')[0]}" in text
        else:
            ok = any(re.search(rf"(?<![\w./]){re.escape(w)}(?![\w])", text) for w in words)
        if not ok:
            out.append(f"{_rel(root, found[name])}: module {name} is not named in docs/"
                       "ARCHITECTURE.md: say where it sits and what it does")
    return out


RULES = [unplaced_modules, upward_imports, import_cycles, confined_imports, witness_imports,
         witness_apart, renamed_imports, oversized, long_docs, broken_references,
         misplaced_tests, unnamed_modules]


# ---------------------------------------------------------------------------------------------
# This checkout keeps every rule
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("rule", RULES, ids=lambda r: r.__name__)
def test_the_house_keeps_the_rule(rule):
    found = rule(ROOT)
    assert not found, f"{rule.__name__}:\n" + "\n".join(found)


def test_the_floors_name_real_modules():
    """A row of FLOORS that names nothing is a rule that guards nothing."""
    found = modules(ROOT)
    stale = [prefix for prefix in FLOORS
             if not any(m == prefix or m.startswith(prefix + ".") for m in found)]
    assert not stale, f"FLOORS rows with no module: {stale}"


# ---------------------------------------------------------------------------------------------
# Each rule catches a planted violation, and names the file and the rule
# ---------------------------------------------------------------------------------------------

def _tree(tmp_path: Path, files: dict[str, str]) -> Path:
    base = {"shadowvol/__init__.py": "", "shadowvol/errors.py": "", "shadowvol/scene.py": "",
            "shadowvol/raster/__init__.py": "", "shadowvol/cli/__init__.py": "",
            "raytrace/__init__.py": ""}
    for rel, text in {**base, **files}.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    return tmp_path


def test_a_clean_planted_tree_keeps_every_rule(tmp_path):
    root = _tree(tmp_path, {"shadowvol/raster/passes.py": "import moderngl\n"
                                                          "from shadowvol.scene import x\n",
                            "raytrace/masks.py": "", "raytrace/outlook/__init__.py": "",
                            "raytrace/outlook/path/pathtrace.py": "from raytrace.masks import x\n"
                                                                  "from raytrace import masks\n"
                                                                  "import numpy as np\n"
                                                                  "import raytrace.masks as masks\n"
                                                                  "from raytrace.masks import x as y\n",
                            "tests/raster/test_passes.py": "from shadowvol.raster import passes\n",
                            "tests/raytrace/test_masks.py": "import raytrace\n",
                            "tests/cli/test_help.py": "run('-m', 'shadowvol', '--help')\n",
                            "tests/system/test_installed.py": "import shadowvol\n",
                            "docs/ARCHITECTURE.md": "`shadowvol/`: `errors`, `scene`, `raster/` "
                                                    "(`passes`), `cli/`; `raytrace/`: `masks`, "
                                                    "`outlook/` (`path/`: `pathtrace`)\n"})
    assert [v for rule in RULES for v in rule(root)] == []


PLANTED = {
    "upward": (upward_imports, {"shadowvol/scene.py": "from shadowvol.raster import passes\n",
                                "shadowvol/raster/passes.py": ""},
               "shadowvol/scene.py:1: imports shadowvol.raster.passes", "runs up"),
    "across": (upward_imports, {"raytrace/masks.py": "import shadowvol.raster.passes\n",
                                "shadowvol/raster/passes.py": ""},
               "raytrace/masks.py:1: imports shadowvol.raster.passes", "runs across"),
    "lazy upward": (upward_imports, {"shadowvol/errors.py": "def f():\n"
                                                            "    from shadowvol import cli\n"},
                    "shadowvol/errors.py:2: imports shadowvol.cli", "runs up"),
    "cycle": (import_cycles, {"shadowvol/raster/a.py": "from shadowvol.raster import b\n",
                              "shadowvol/raster/b.py": "from . import a\n"},
              "import cycle shadowvol.raster.a <-> shadowvol.raster.b", "shadowvol/raster/a.py"),
    "GL outside raster": (confined_imports, {"shadowvol/scene.py": "import moderngl\n"},
                          "shadowvol/scene.py:1: imports moderngl", "shadowvol/raster/"),
    "ctypes outside raster": (confined_imports, {"raytrace/fast.py": "import ctypes.util\n"},
                              "raytrace/fast.py:1: imports ctypes.util", "shadowvol/raster/"),
    "ctypes in the witness beside its Embree file": (
        confined_imports, {"raytrace/embree4.py": "import ctypes\n",
                           "raytrace/masks.py": "from ctypes import c_float\n"},
        "raytrace/masks.py:1: imports ctypes", "raytrace/embree4.py"),
    "EGL outside raster": (confined_imports, {"shadowvol/cli/x.py": "from OpenGL import EGL\n"},
                           "shadowvol/cli/x.py:1: imports OpenGL", "shadowvol/raster/"),
    "argparse outside cli": (confined_imports, {"raytrace/cli.py": "import argparse\n"},
                             "raytrace/cli.py:1: imports argparse", "shadowvol/cli/"),
    "witness": (witness_imports, {"raytrace/x.py": "from shadowvol import scenefile\n",
                                  "shadowvol/scenefile.py": ""},
                "raytrace/x.py:1: the witness imports shadowvol.scenefile", "only the model"),
    "witness apart": (witness_apart,
                      {"raytrace/masks.py": "from raytrace.outlook import whitted\n",
                       "raytrace/outlook/__init__.py": "", "raytrace/outlook/whitted.py": ""},
                      "raytrace/masks.py:1: the witness imports raytrace.outlook.whitted",
                      "never the reverse"),
    "witness apart, lazily": (witness_apart,
                              {"raytrace/soft.py": "def f():\n"
                                                   "    import raytrace.outlook.path.sobol\n",
                               "raytrace/outlook/path/sobol.py": ""},
                              "raytrace/soft.py:2: the witness imports raytrace.outlook.path.sobol",
                              "global illumination"),
    "renamed module": (renamed_imports, {"shadowvol/cli/render.py": "from shadowvol.cli import "
                                                                    "args as blocks\n",
                                         "shadowvol/cli/args.py": ""},
                       "shadowvol/cli/render.py:1: imports the module shadowvol.cli.args as "
                       "blocks", "its own name"),
    "renamed module, relative and lazily": (
        renamed_imports, {"benchmarks/__init__.py": "", "benchmarks/timing.py": "",
                          "benchmarks/run.py": "def f():\n    from . import timing as t\n"},
        "benchmarks/run.py:2: imports the module benchmarks.timing as t", "its own name"),
    "unplaced": (unplaced_modules, {"shadowvol/util.py": ""},
                 "shadowvol/util.py: module shadowvol.util has no floor", "FLOORS"),
    "long module": (oversized, {"shadowvol/scene.py": "x = 1\n" * 501},
                    "shadowvol/scene.py: 501 lines", "500 a module"),
    "long function": (oversized, {"raytrace/x.py": "def f():\n" + "    x = 1\n" * 80},
                      "raytrace/x.py:1: function f is 81 lines", "80 a function"),
    "long README": (long_docs, {"README.md": "line\n" * 201}, "README.md: 201 lines", "200"),
    "path in a doc": (broken_references, {"README.md": "See shadowvol/raster/gone.py.\n"},
                      "README.md:1: names shadowvol/raster/gone.py", "does not exist"),
    "path in a docstring": (broken_references,
                            {"raytrace/x.py": '"""Mirrors raster/truth.py."""\n'},
                            "raytrace/x.py:1: names raster/truth.py", "does not exist"),
    "module in a comment": (broken_references,
                            {"raytrace/x.py": "x = 1  # as shadowvol.course.planar does\n",
                             "shadowvol/course/__init__.py": ""},
                            "raytrace/x.py:1: names shadowvol.course.planar", "does not exist"),
    "module run": (broken_references, {"docs/x.md": "Run `python -m benchmarks.gone`.\n",
                                       "benchmarks/__init__.py": ""},
                   "docs/x.md:1: runs python -m benchmarks.gone", "does not exist"),
    "misplaced test": (misplaced_tests, {"tests/cli/test_memory.py": "from shadowvol import memory\n",
                                         "shadowvol/memory.py": ""},
                       "tests/cli/test_memory.py: uses nothing of its wing tests/cli/ (it uses: "
                       "scene)", "the wing of what it tests"),
    "witness test of the outlook": (misplaced_tests,
                                    {"tests/raytrace/test_whitted.py":
                                     "import raytrace\nfrom raytrace.outlook import whitted\n",
                                     "raytrace/outlook/__init__.py": "",
                                     "raytrace/outlook/whitted.py": ""},
                                    "tests/raytrace/test_whitted.py: a test of the witness uses "
                                    "raytrace.outlook.whitted", "tests/raytrace/outlook/"),
    "system test inside": (misplaced_tests,
                           {"tests/system/test_readme.py": "from shadowvol.raster import passes\n",
                            "shadowvol/raster/passes.py": ""},
                           "tests/system/test_readme.py: a whole-product test imports "
                           "shadowvol.raster.passes", "tests that module's wing (raster)"),
    "test in no wing": (misplaced_tests, {"tests/misc/test_x.py": "import shadowvol\n"},
                        "tests/misc/test_x.py: tests/misc/ is no wing", "TEST_WINGS"),
    "module not in ARCHITECTURE.md": (unnamed_modules,
                                      {"docs/ARCHITECTURE.md": "`shadowvol/`: `errors`, `scene`, "
                                                               "`raster/` (`passes`), `cli/`; "
                                                               "`raytrace/`\n",
                                       "shadowvol/raster/passes.py": "",
                                       "raytrace/masks.py": ""},
                                      "raytrace/masks.py: module raytrace.masks is not named",
                                      "docs/ARCHITECTURE.md"),
    "shared stem unqualified": (unnamed_modules,
                                {"docs/ARCHITECTURE.md": "`shadowvol/`: `errors`, `scene`, "
                                                         "`raster/` (`estimate`), `cli/`; "
                                                         "`raytrace/`: `raytrace/estimate`\n",
                                 "shadowvol/raster/estimate.py": "",
                                 "raytrace/estimate.py": ""},
                                "shadowvol/raster/estimate.py: module shadowvol.raster.estimate "
                                "is not named", "ARCHITECTURE.md"),
    "name in a module": (broken_references,
                         {"README.md": "`shadowvol.scene.Gone` is\n"},
                         "README.md:1: names shadowvol.scene.Gone", "does not exist"),
}


@pytest.mark.parametrize("case", PLANTED)
def test_each_rule_catches_a_planted_violation(tmp_path, case):
    rule, files, where, what = PLANTED[case]
    found = rule(_tree(tmp_path, files))
    assert len(found) == 1 and where in found[0] and what in found[0], found


def test_references_that_exist_are_not_flagged(tmp_path):
    root = _tree(tmp_path, {
        "shadowvol/raster/truth.py": '"""See shadowvol/scene.py, shadowvol.scene.Camera."""\n',
        "shadowvol/scene.py": "class Camera:\n    pass\n",
        "README.md": "[a](docs/x.md#part), out/cage.png, `shadowvol.raster.truth`, scenes/*.toml\n"
                     "python -m shadowvol render, python -m benchmarks.run\n",
        "docs/x.md": "[back](../README.md)\n", "shadowvol/__main__.py": "",
        "benchmarks/run.py": ""})
    assert broken_references(root) == []
