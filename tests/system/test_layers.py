"""The layers at run time: the ray tracer renders with GL and pyrender blocked, importing either
package costs no GL, trimesh or matplotlib, and the public API is what the docs say.  (Who may
import what is read from the sources by tests/test_architecture.py.)"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
from builders import ROOT, SCENES

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


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)


def test_raytrace_renders_with_gl_and_pyrender_blocked(tmp_path):
    code = BLOCK.replace("NAMES", repr(("moderngl", "glcontext", "pyrender", "OpenGL"))) + textwrap.dedent(f"""
        import raytrace
        from shadowvol.cli.raytrace import main
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


def test_drawing_an_exercise_leaves_matplotlibs_backend_alone():
    done = _python(textwrap.dedent("""
        import matplotlib
        matplotlib.use("svg")
        from raytrace import exercise
        from shadowvol.course.exercise_picture import plane_figure
        fig = plane_figure(exercise.solve_plane())
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
