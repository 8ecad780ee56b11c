"""The documentation: pdoc builds the API reference of every module of `shadowvol` and `raytrace`
from their docstrings with no warning, and documents every public name of `shadowvol`; every
backticked `module.NAME` in the docs is a real attribute of a real module.  (That every name and
path the docs and docstrings name exists is a house rule: tests/test_architecture.py.)

Build the reference yourself with `python tests/test_docs.py docs/api` (not committed: it is
generated).  pdoc imports every module; none needs an optional extra to be imported.
"""

import importlib
import os
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("shadowvol", "raytrace")

# pdoc cannot evaluate a NamedTuple's postponed annotations (`from __future__ import annotations`)
# for its generated constructor (mitmproxy/pdoc#765): the annotation is fine, pdoc's lookup is not
NAMEDTUPLE_REF = re.compile(r"Error parsing type annotation .* for ([\w.]+)\.__init__\. Import of")


def module_names() -> list[str]:
    """Every module of the two packages, found on disk (a package's `__all__` does not hide one)."""
    names = list(PACKAGES)
    for package in PACKAGES:
        path = [str(ROOT / package)]
        names += [m.name for m in pkgutil.walk_packages(path, package + ".")
                  if not m.name.endswith(".__main__")]
    return names


def _known_false_alarm(message: str) -> bool:
    match = NAMEDTUPLE_REF.search(message)
    if not match:
        return False
    module, _, name = match.group(1).rpartition(".")
    cls = getattr(importlib.import_module(module), name, None)
    return isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")


def build(out: Path) -> list[str]:
    """Write the reference into `out`; return pdoc's warnings."""
    import warnings

    import pdoc.doc
    import pdoc.render

    import raytrace
    import shadowvol

    problems = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # pdoc reads a module's __dict__, not its PEP 562 __getattr__: resolve the lazy names first
        for package in (shadowvol, raytrace):
            for name in package.__all__:
                getattr(package, name)
        modules = {name: pdoc.doc.Module.from_name(name) for name in module_names()}
        for module in modules.values():
            page = out / f"{module.fullname.replace('.', '/')}.html"
            page.parent.mkdir(parents=True, exist_ok=True)
            page.write_text(pdoc.render.html_module(module, modules))
        (out / "index.html").write_text(pdoc.render.html_index(modules))
        (out / "search.js").write_text(pdoc.render.search_index(modules))
    problems += [f"pdoc: {w.message}" for w in caught if not _known_false_alarm(str(w.message))]
    return problems


# The docs whose backticked `module.NAME` references are resolved (as tests/test_architecture.py
# reads them for paths).
DOCS = ("README.md", "BENCHMARKS.md", "docs/*.md", "docs/benchmarks/*.md", "scenes/README.md",
        "benchmarks/*.md")
# `a.b` or `a.b.c`, with `()` after a call: a module of the project, then names in it.
BACKTICKED = re.compile(r"`([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?:\(\))?`")
# `scene.toml`, `run.py`: a file, not a name
FILE_ENDINGS = {"py", "toml", "json", "jsonl", "png", "npz", "npy", "md", "exr", "obj", "ply",
                "stl", "off", "glb", "gltf", "bin", "txt", "tar", "html", "ipynb", "csv", "jpg"}
# the same spelling, but not the module of that name
NOT_MODULES = {"jitter.objects": "a job file's key (docs/formats.md), not shadowvol.batch.jitter",
               "jitter.objects.scale": "a job file's key",
               "ray.init": "the Ray library's, not shadowvol.batch.ray",
               "scene.camera": "a trimesh.Scene's attribute, not shadowvol.scene",
               "scene.camera_transform": "a trimesh.Scene's attribute"}


def every_module() -> list[str]:
    """The modules a doc may name: both packages' and the benchmarks'."""
    names = module_names() + ["benchmarks"]
    names += [m.name for m in pkgutil.walk_packages([str(ROOT / "benchmarks")], "benchmarks.")]
    return [n for n in names if not n.endswith(".__main__")]


def _has(obj, name: str) -> bool:
    """An attribute, or an instance attribute its class declares (a dataclass field)."""
    if hasattr(obj, name):
        return True
    return isinstance(obj, type) and any(name in vars(k).get("__annotations__", {})
                                         or name in getattr(k, "__slots__", ())
                                         for k in obj.__mro__)


def resolves(reference: str, modules: list[str]) -> bool | None:
    """Whether `a.b.NAME` is a real attribute: the longest head of it that ends the dotted name of
    some module, then each further name an attribute (any one module of that head will do);
    None where no head names a module (not a reference to this project)."""
    parts = reference.split(".")
    for k in range(len(parts), 0, -1):
        head = ".".join(parts[:k])
        found = [m for m in modules if m == head or m.endswith("." + head)]
        if found:
            break
    else:
        return None
    for module in found:
        obj = importlib.import_module(module)
        for name in parts[k:]:
            if not _has(obj, name):
                break
            obj = getattr(obj, name, None)
        else:
            return True
    return False


def unresolved(lines, modules: list[str]) -> list[str]:
    """One line per backticked `module.NAME` of (file, line, text) that names nothing real."""
    out = []
    for source, number, text in lines:
        for match in BACKTICKED.finditer(text):
            reference = match.group(1)
            if reference.rpartition(".")[2] in FILE_ENDINGS or reference in NOT_MODULES:
                continue
            if resolves(reference, modules) is False:
                out.append(f"{source}:{number}: `{reference}` is no attribute of a module of this "
                           "project")
    return out


def doc_lines():
    for pattern in DOCS:
        for path in sorted(ROOT.glob(pattern)):
            for number, text in enumerate(path.read_text().splitlines(), 1):
                yield path.relative_to(ROOT).as_posix(), number, text


def test_backticked_names_are_real_attributes():
    found = unresolved(doc_lines(), every_module())
    assert not found, "\n".join(found)


def test_a_name_that_is_not_there_is_caught():
    """Planted: `store.gone` (no such name in shadowvol.batch.store) among real references, a
    file name and a key spelled like a module."""
    lines = [("docs/x.md", 1, "`store.put`, `batch.store.Store`, `raytrace.shadow_masks()`, "
                              "`store.gone`, `scene.toml`, `jitter.objects`, `np.float32`"),
             ("docs/x.md", 2, "`shadowvol.lights.AreaLight.positions` (a field)")]
    assert unresolved(lines, every_module()) == [
        "docs/x.md:1: `store.gone` is no attribute of a module of this project"]


def test_api_reference_builds_without_a_warning(tmp_path):
    """In a fresh process, as pdoc imports every module (GL modules import moderngl, no more)."""
    env = {**os.environ,
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, str(Path(__file__)), str(tmp_path)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    pages = {p.relative_to(tmp_path).with_suffix("").as_posix().replace("/", ".")
             for p in tmp_path.rglob("*.html")}
    assert set(module_names()) <= pages, sorted(set(module_names()) - pages)
    import shadowvol

    front = (tmp_path / "shadowvol.html").read_text()  # the public API documented on its page
    assert all(f'<section id="{name}">' in front for name in shadowvol.__all__)


if __name__ == "__main__":
    found = build(Path(sys.argv[1]))
    print("\n".join(found))
    sys.exit(1 if found else 0)
