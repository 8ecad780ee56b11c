"""The traps new users hit (issue "Layers you can see"), each fixed and kept fixed."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from builders import ROOT, SCENES

import shadowvol
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.scenefile import load_scene, save_scene

pytestmark = pytest.mark.gl


def _python(code: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def test_pyrender_after_a_one_shot_render():
    """A released one-shot context was left "current"; pyrender's restore of it failed with
    EGL_BAD_CONTEXT (12294).  Also after a user's own OffscreenRenderer.delete()."""
    done = _python(f"""
        import shadowvol
        from shadowvol.compare.pyrender_peer import (maskable_lights, pyrender_shadow_masks,
                                                     render_pyrender)
        scene = shadowvol.load_scene({str(SCENES / "stack.toml")!r}).replace(width=48, height=36)
        shadowvol.render(scene)
        image = render_pyrender(scene)
        lit, cov = pyrender_shadow_masks(scene, lights=maskable_lights(scene))
        assert image.shape == (36, 48, 3) and cov.any()
        shadowvol.render(scene)          # and the rasterizer still works after pyrender
        """)
    assert done.returncode == 0, done.stderr


def test_a_fork_after_a_context_is_a_clear_error_not_a_hang(tmp_path):
    script = tmp_path / "pool.py"  # spawn re-imports __main__: it must be a file
    script.write_text(textwrap.dedent(f"""
        import multiprocessing as mp, shadowvol
        scene = shadowvol.load_scene({str(SCENES / "cage.toml")!r}).replace(width=16, height=12)
        def work(_):
            try:
                return repr(shadowvol.render(scene).lit.shape)
            except Exception as exc:
                return type(exc).__name__ + ": " + str(exc)
        if __name__ == "__main__":
            shadowvol.render(scene)
            with mp.get_context("fork").Pool(1) as pool:
                print(pool.map(work, [0])[0])
            with mp.get_context("spawn").Pool(1) as pool:
                print(pool.map(work, [0])[0])
        """))
    done = subprocess.run([sys.executable, str(script)], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    forked, spawned = done.stdout.strip().splitlines()
    assert forked.startswith("ForkedContextError:") and "spawn" in forked
    assert spawned == "(1, 12, 16)"


def test_compare_pyrender_without_the_extra(tmp_path):
    done = _python(f"""
        import sys
        class Block:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] == "pyrender":
                    raise ImportError("No module named 'pyrender'", name="pyrender")
        sys.meta_path.insert(0, Block())
        from shadowvol.cli.main import main
        sys.exit(main(["compare", {str(SCENES / "cage.toml")!r}, "--pyrender", "-o",
                       {str(tmp_path / "c.png")!r}]))
        """)
    assert done.returncode == 2
    assert done.stderr.strip() == ("error: pyrender's shadow maps (compare --pyrender) needs the "
                                   "optional package 'pyrender', which is not installed: "
                                   "pip install 'shadowvol[peer]'")


def test_volume_view_takes_light_objects_like_render(ctx):
    scene = load_scene(SCENES / "stack.toml").replace(width=64, height=48)
    with shadowvol.Renderer(scene, ctx) as r:
        alone = r.volume_view(lights=(scene.lights[0],))
        both = r.volume_view()
        plain = r.render(lights=(scene.lights[0],)).image
        with pytest.raises(TypeError, match="Light objects"):
            r.volume_view(lights=(0,))
        with pytest.raises(TypeError, match="Light objects"):
            r.render(lights=(0,))
    assert not np.array_equal(alone, plain)  # its polygons are drawn
    assert not np.array_equal(alone, both)


def test_the_public_face_needs_no_prior_touch():
    done = _python("import shadowvol; print(shadowvol.Renderer.__name__, "
                   "shadowvol.render.__module__)")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["Renderer", "shadowvol.raster.renderer"]


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_save_scene_writes_the_format_its_name_says(tmp_path, suffix):
    scene = load_scene(SCENES / "stack.toml")
    path = tmp_path / f"copy{suffix}"
    shadowvol.save_scene(scene, path)
    text = path.read_text()
    if suffix == ".json":
        json.loads(text)
    else:
        import tomllib
        tomllib.loads(text)
    again = load_scene(path)
    assert [o.name for o in again.objects] == [o.name for o in scene.objects]
    for a, b in zip(again.objects, scene.objects):
        np.testing.assert_array_equal(a.vertices, b.vertices)  # bit for bit
    np.testing.assert_array_equal(again.camera.eye, scene.camera.eye)
    with pytest.raises(shadowvol.SceneError, match="must end in .toml or .json"):
        shadowvol.save_scene(scene, tmp_path / "copy.yaml")


@pytest.mark.parametrize("flag, name", [("-o", "t.jpg"), ("--masks", "m.png"),
                                        ("--volumes", "v.npz"), ("--stencil", "s.tiff")])
def test_output_names_are_checked_before_any_work(tmp_path, capsys, flag, name):
    scene = str(SCENES / "cage.toml")
    args = ["render", scene, "-o", str(tmp_path / "x.png"), flag, str(tmp_path / name)]
    if flag == "-o":
        args = ["render", scene, "-o", str(tmp_path / name)]
    assert shadowvol_main(args) == 2
    assert f"{flag}: " in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_masks_and_image_may_not_be_one_file(tmp_path, capsys):
    path = str(tmp_path / "x.npz")
    assert shadowvol_main(["render", str(SCENES / "cage.toml"), "-o", str(tmp_path / "x.png"),
                           "--masks", path, "--volumes", str(tmp_path / "x.png")]) == 2
    assert "also the -o output" in capsys.readouterr().err


def test_masks_flag_before_the_scene(tmp_path):
    small = tmp_path / "cage.json"
    save_scene(load_scene(SCENES / "cage.toml").replace(width=32, height=24), small)
    assert shadowvol_main(["render", "--masks", str(small), "-o", str(tmp_path / "x.png")]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cage.json", "x-masks.npz", "x.png"]


def test_scenes_readme_links_to_the_project_conventions():
    text = (SCENES / "README.md").read_text()
    assert "shared/CONVENTIONS.md" not in text and "../docs/CONVENTIONS.md" in text
    assert (SCENES / "../docs/CONVENTIONS.md").exists()
