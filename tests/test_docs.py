"""The documentation: pdoc builds the API reference of every module of `shadowvol` and `raytrace`
from their docstrings with no warning, and every `shadowvol.…` / `raytrace.…` name and every path
that a docstring, the README, docs/*.md or scenes/README.md names exists.

Build the reference yourself with `python tests/test_docs.py docs/api` (not committed: it is
generated).  pdoc imports every module; none needs an optional extra to be imported.
"""

import importlib
import os
import pkgutil
import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("shadowvol", "raytrace")

# pdoc cannot evaluate a NamedTuple's postponed annotations (`from __future__ import annotations`)
# for its generated constructor (mitmproxy/pdoc#765): the annotation is fine, pdoc's lookup is not
NAMEDTUPLE_REF = re.compile(r"Error parsing type annotation .* for ([\w.]+)\.__init__\. Import of")
DOTTED_REF = re.compile(r"`((?:shadowvol|raytrace)(?:\.[A-Za-z_]\w*)+)`")
# in a document, a name starts a code span (`shadowvol.batch.run(jobs, ...)`) or follows python -m
DOC_NAME = re.compile(r"`((?:shadowvol|raytrace)(?:\.[A-Za-z_]\w*)+)|python -m ([\w.]+)")
# a path a document names: a link target, or a backticked or bare token under one of our folders
DOC_PATH = re.compile(r"\]\(([^)#\s]+)|(?<![\w./-])((?:shadowvol|raytrace|scenes|docs|tests|"
                      r"benchmarks|shaders|\.ci)/[\w./-]*\w)")


def documents() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "scenes" / "README.md"]


def module_names() -> list[str]:
    """Every module of the two packages, found on disk (a package's `__all__` does not hide one)."""
    names = list(PACKAGES)
    for package in PACKAGES:
        path = [str(ROOT / package)]
        names += [m.name for m in pkgutil.walk_packages(path, package + ".")
                  if not m.name.endswith(".__main__")]
    return names


def _data_packages() -> set[str]:
    """The packages that exist only once installed (pyproject's package-dir: shaders, scenes)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    return {name for name, folder in config["package-dir"].items() if (ROOT / folder).is_dir()}


def _resolves(dotted: str, data: set[str]) -> bool:
    if dotted in data:
        return True
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            if isinstance(obj, type) and not hasattr(obj, part):
                # an instance attribute the class declares (a dataclass field with init=False)
                return any(part in vars(c).get("__annotations__", {}) for c in obj.__mro__)
            if not hasattr(obj, part):
                return False
            obj = getattr(obj, part)
        return True
    return False


def _docstrings(namespace):
    import pdoc.doc

    yield namespace.fullname, namespace.docstring
    for member in namespace.own_members:
        if isinstance(member, pdoc.doc.Class):
            yield from _docstrings(member)
        else:
            yield member.fullname, member.docstring


def _known_false_alarm(message: str) -> bool:
    match = NAMEDTUPLE_REF.search(message)
    if not match:
        return False
    module, _, name = match.group(1).rpartition(".")
    cls = getattr(importlib.import_module(module), name, None)
    return isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")


def build(out: Path) -> list[str]:
    """Write the reference into `out`; return every problem found (pdoc's warnings, broken names)."""
    import warnings

    import pdoc.doc
    import pdoc.render

    import shadowvol

    problems = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # pdoc reads a module's __dict__, not its PEP 562 __getattr__: resolve the lazy names first
        for name in shadowvol.__all__:
            getattr(shadowvol, name)
        modules = {name: pdoc.doc.Module.from_name(name) for name in module_names()}
        for module in modules.values():
            page = out / f"{module.fullname.replace('.', '/')}.html"
            page.parent.mkdir(parents=True, exist_ok=True)
            page.write_text(pdoc.render.html_module(module, modules))
        (out / "index.html").write_text(pdoc.render.html_index(modules))
        (out / "search.js").write_text(pdoc.render.search_index(modules))
    problems += [f"pdoc: {w.message}" for w in caught if not _known_false_alarm(str(w.message))]
    data = _data_packages()
    for module in modules.values():
        for where, text in _docstrings(module):
            problems += [f"{where}'s docstring names `{ref}`, which does not exist"
                         for ref in DOTTED_REF.findall(text or "") if not _resolves(ref, data)]
    for doc in documents():
        for name, module in DOC_NAME.findall(doc.read_text()):
            if not _resolves(name or module, data):
                problems.append(f"{doc.relative_to(ROOT)} names {name or module}, which does not exist")
    return problems


def test_api_reference_builds_without_a_warning_and_every_name_exists(tmp_path):
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


def test_docs_name_only_paths_that_exist():
    missing = []
    for doc in documents():
        for link, token in DOC_PATH.findall(doc.read_text()):
            path = link or token
            if "://" in path or path.startswith("mailto:"):
                continue
            if not ((doc.parent if link else ROOT) / path).exists():  # a link is relative
                missing.append(f"{doc.relative_to(ROOT)}: {path}")
    assert not missing, "documents name paths that do not exist:\n" + "\n".join(missing)


if __name__ == "__main__":
    found = build(Path(sys.argv[1]))
    print("\n".join(found))
    sys.exit(1 if found else 0)
