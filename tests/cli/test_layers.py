"""The layer rules of docs/ARCHITECTURE.md: who may import GL, what `raytrace` may import from
shadowvol, and what importing either package costs."""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap

import pytest
from builders import ROOT, SCENES

GL_MODULES = ("moderngl", "glcontext")
# what raytrace may use of shadowvol: the model, the writers, the exit-status table
RAYTRACE_MAY_IMPORT = {"shadowvol", "shadowvol.scene", "shadowvol.primitives", "shadowvol.cameras",
                       "shadowvol.scenefile", "shadowvol.resources", "shadowvol.errors",
                       "shadowvol.memory", "shadowvol.fields",
                       "shadowvol.io", "shadowvol.pictures", "shadowvol.cli",
                       "shadowvol.cli.status", "shadowvol.cli.outputs"}

# a meta path finder that makes importing the named top-level packages fail
BLOCK = textwrap.dedent("""
    import sys
    class Block:
        def __init__(self, names): self.names = set(names)
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in self.names:
                raise ImportError("blocked for the test: " + name, name=name)
    sys.meta_path.insert(0, Block(NAMES))
    """)


def _imports(path) -> set[str]:
    text = path.read_text()
    found = set(re.findall(r"^\s*import ([\w.]+)", text, flags=re.M))
    found |= set(re.findall(r"^\s*from ([\w.]+) import", text, flags=re.M))
    return found


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)


def test_only_the_raster_wing_and_the_pyrender_peer_import_gl():
    offenders = []
    for path in sorted((ROOT / "shadowvol").rglob("*.py")) + sorted((ROOT / "raytrace").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        allowed = rel.startswith("shadowvol/raster/") or rel == "shadowvol/compare/pyrender_peer.py"
        gl = {m for m in _imports(path) if m.split(".")[0] in GL_MODULES}
        if gl and not allowed:
            offenders.append((rel, sorted(gl)))
    assert not offenders, f"GL imported outside shadowvol/raster/: {offenders}"


def test_raytrace_imports_only_the_model_io_pictures_and_status():
    offenders = []
    for path in sorted((ROOT / "raytrace").rglob("*.py")):
        used = {m for m in _imports(path) if m.split(".")[0] == "shadowvol"}
        if used - RAYTRACE_MAY_IMPORT:
            offenders.append((path.name, sorted(used - RAYTRACE_MAY_IMPORT)))
    assert not offenders, f"raytrace reaches into the rasterizer: {offenders}"


def test_raytrace_renders_with_gl_and_pyrender_blocked(tmp_path):
    code = BLOCK.replace("NAMES", repr(("moderngl", "glcontext", "pyrender", "OpenGL"))) + textwrap.dedent(f"""
        import raytrace
        from raytrace.cli import main
        from shadowvol.scenefile import load_scene
        scene = load_scene({str(SCENES / "cage.toml")!r}).replace(width=32, height=24)
        image = raytrace.render(scene, progress=False)
        lit, coverage = raytrace.shadow_masks(scene)
        assert image.shape == (24, 32, 3) and lit.shape == (1, 24, 32) and coverage.any()
        assert main(["masks", {str(SCENES / "whitted.toml")!r}, "-o",
                     {str(tmp_path / "m.npz")!r}]) == 0
        assert not [m for m in sys.modules if m.split(".")[0] in ("moderngl", "glcontext")]
        """)
    done = _python(code)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "m.npz").exists()


@pytest.mark.parametrize("package", ["shadowvol", "raytrace"])
def test_importing_a_package_loads_no_gl_trimesh_or_matplotlib(package):
    done = _python(f"import sys, {package}; print(sorted(m for m in sys.modules "
                   "if m.split('.')[0] in ('moderngl', 'glcontext', 'trimesh', 'matplotlib', "
                   "'pyrender')))")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_drawing_a_ray_tree_leaves_matplotlibs_backend_alone():
    done = _python(textwrap.dedent(f"""
        import matplotlib
        matplotlib.use("svg")
        from raytrace.raytree import draw_tree, ray_tree
        from shadowvol.scenefile import load_scene
        scene = load_scene({str(SCENES / "whitted.toml")!r}).replace(width=64, height=48)
        fig = draw_tree(scene, ray_tree(scene, 30, 20, max_depth=1))
        import io; fig.savefig(io.BytesIO(), format="png")
        print(matplotlib.get_backend())
        """))
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "svg"


def test_the_public_api():
    import shadowvol

    for name in ("Renderer", "render", "load_scene", "save_scene", "save_png", "save_masks",
                 "example_scene", "__version__", "Scene", "SceneError"):
        assert hasattr(shadowvol, name), name
    assert shadowvol.example_scene("cage").name == "cage.toml"
    with pytest.raises(shadowvol.SceneError, match="the examples are .*cage"):
        shadowvol.example_scene("no such scene")
    for module in ("shadowvol", "raytrace"):
        done = subprocess.run([sys.executable, "-m", module, "--version"], capture_output=True,
                              text=True, timeout=60)
        assert done.returncode == 0 and shadowvol.__version__ in done.stdout
