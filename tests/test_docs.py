"""The documentation: pdoc builds the API reference of every module of `shadowvol` and `raytrace`
from their docstrings with no warning, and documents every public name of `shadowvol`.  (That
every name and path the docs and docstrings name exists is a house rule: tests/
test_architecture.py.)

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
