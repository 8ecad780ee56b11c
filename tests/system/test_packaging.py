"""What a plain `pip install .` gives a user: the command-line tools must work with the runtime
dependencies alone.  Test-only packages are installed in CI, so without this check a stray
import of one of them (scipy once was) passes CI and breaks the README's first command."""

import subprocess
import sys
import textwrap

import pytest
from builders import SCENES

pytestmark = pytest.mark.gl  # the child processes render

TEST_ONLY = ("scipy", "pyrender", "hypothesis", "pytest", "OpenGL")


def test_runtime_needs_no_test_only_package():
    code = textwrap.dedent(f"""
        import importlib.abc, sys
        class Block(importlib.abc.MetaPathFinder):
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in {TEST_ONLY!r}:
                    raise ImportError(f"test-only package imported at run time: {{name}}")
        for name in list(sys.modules):
            if name.split(".")[0] in {TEST_ONLY!r}:
                del sys.modules[name]
        sys.meta_path.insert(0, Block())
        import shadowvol.cli.main, shadowvol.cli.raytrace
        shadowvol.cli.main.build_parser()
        for argv in (["render", "--help"], ["compare", "--help"]):
            try:
                shadowvol.cli.main.main(argv)
            except SystemExit as e:
                assert e.code == 0, (argv, e.code)
        for argv in (["render", "--help"], ["masks", "--help"], ["tree", "--help"]):
            try:
                shadowvol.cli.raytrace.main(argv)
            except SystemExit as e:
                assert e.code == 0, (argv, e.code)
        import raytrace, shadowvol, shadowvol.compare.comparison, shadowvol.raster.overflow.detect
        from shadowvol.scenefile import load_scene
        # run, not only import: the libraries import some of their dependencies lazily
        # (trimesh's convexity test needs scipy, which once broke `shadowvol render`)
        scene = load_scene({str(SCENES / "cage.toml")!r}).replace(width=32, height=24)
        frame = shadowvol.render(scene)
        lit, coverage = raytrace.shadow_masks(scene)
        raytrace.render(scene.replace(max_depth=1))
        shadowvol.compare.comparison.compare(scene)
        assert shadowvol.raster.overflow.detect.count_bound([]) == 0
        assert frame.lit.shape == lit.shape
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip().endswith("ok"), out.stderr[-3000:]
