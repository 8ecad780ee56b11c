"""A frame the GL cannot allocate is one clear error (exit 3), not "framebuffer incomplete"."""

from __future__ import annotations

import moderngl
import pytest
from builders import SCENES

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.raster import target as target_module
from shadowvol.raster.platform.gl import RawGL
from shadowvol.scenefile import load_scene, save_scene


class _RefusingContext:
    """The context, refusing its n-th texture as a driver out of memory would."""

    def __init__(self, ctx, refuse_at: int):
        self._ctx, self._left = ctx, refuse_at

    def texture(self, *args, **kwargs):
        self._left -= 1
        if self._left == 0:
            raise moderngl.Error("the framebuffer is not complete (INCOMPLETE_ATTACHMENT)")
        return self._ctx.texture(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._ctx, name)


@pytest.mark.parametrize("refuse_at", [1, 3, 5])
def test_a_refused_allocation_names_the_size_and_frees_what_it_made(ctx, refuse_at):
    textures_before = len([o for o in ctx.objects if isinstance(o, moderngl.Texture)]) \
        if hasattr(ctx, "objects") else None
    with pytest.raises(target_module.FrameAllocationError,
                       match=r"could not allocate a 640x480 frame \(about 15 MiB"):
        target_module.Target(_RefusingContext(ctx, refuse_at), RawGL(), 640, 480)
    assert ctx.error == "GL_NO_ERROR"
    if textures_before is not None:
        assert len([o for o in ctx.objects if isinstance(o, moderngl.Texture)]) == \
            textures_before
    target_module.Target(ctx, RawGL(), 64, 48).release()  # the context is still usable


def test_the_cli_says_so_with_status_3(tmp_path, monkeypatch, capsys):
    path = tmp_path / "s.json"
    save_scene(load_scene(SCENES / "cage.toml").replace(width=64, height=48), path)
    real = target_module.Target.__init__

    def refusing(self, ctx, gl, width, height, **kwargs):
        real(self, _RefusingContext(ctx, 2), gl, width, height, **kwargs)
    monkeypatch.setattr(target_module.Target, "__init__", refusing)
    assert shadowvol_main(["render", str(path), "-o", str(tmp_path / "x.png")]) == 3
    err = capsys.readouterr().err
    assert err.startswith("error: the GL could not allocate a 64x48 frame") and \
        err.count("\n") == 1
    assert not (tmp_path / "x.png").exists()


def test_the_renderer_refuses_a_frame_wider_than_the_gl_as_bad_input(ctx):
    """Every caller of the Renderer (the CLI, batch, Python) gets the GL's size limit as a
    SceneError on `image` (exit 2), before anything is allocated."""
    from shadowvol.raster.renderer import Renderer
    from shadowvol.scene import SceneError

    scene = load_scene(SCENES / "cage.toml").replace(width=40000, height=8)
    with pytest.raises(SceneError, match=r"^image: 40000x8 is larger than this GL allows "
                                         r"\(\d+ pixels per side\)$"):
        Renderer(scene, ctx)
    assert ctx.error == "GL_NO_ERROR"


def test_a_failed_frame_leaves_no_gl_error_for_the_next(ctx, monkeypatch):
    """A frame the GL could not allocate (the size check passed, as a driver may claim more
    than it can make) fails with status 3 and leaves the context's error flags clear: the next
    renderer on the context renders what it renders on a clean one."""
    from shadowvol.raster.renderer import Renderer

    scene = load_scene(SCENES / "cage.toml").replace(width=40, height=30)
    with Renderer(scene, ctx) as r:
        want = r.render().image
    monkeypatch.setattr("shadowvol.raster.renderer.check_frame_size",
                        lambda ctx, width, height: None, raising=False)
    with pytest.raises(target_module.FrameAllocationError, match="40000x8"):
        Renderer(scene.replace(width=40000, height=8), ctx)
    assert ctx.error == "GL_NO_ERROR"
    with Renderer(scene, ctx) as r:
        assert (r.render().image == want).all()


def test_more_objects_than_the_gl_allows_is_blamed_on_the_objects(ctx, tmp_path, capsys):
    """One row of the materials' texture per object: past GL_MAX_TEXTURE_SIZE objects the
    scene is refused naming `objects` and the limit (was: "could not allocate a 8x6 frame",
    the texture's GL error read by the frame's allocation)."""
    import dataclasses

    import numpy as np

    from shadowvol.primitives import mesh
    from shadowvol.raster.renderer import Renderer
    from shadowvol.scene import Camera, PointLight, Scene, SceneError

    n = ctx.info["GL_MAX_TEXTURE_SIZE"] + 1
    one = mesh(name="t", vertices=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]),
               faces=np.array([[0, 1, 2]]))
    scene = Scene(camera=Camera(eye=[0, 0, 3], target=[0, 0, 0]), width=8, height=6,
                  objects=[dataclasses.replace(one, name=f"t{i}") for i in range(n)],
                  lights=[PointLight(position=[0, 0, 2])])
    with pytest.raises(SceneError, match=rf"^objects: {n:,} objects, more than this GL allows "
                                         rf"\({n - 1:,}: "):
        Renderer(scene, ctx)
    assert ctx.error == "GL_NO_ERROR"
    path = tmp_path / "many.json"
    save_scene(scene, path)
    assert shadowvol_main(["render", str(path), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {path}: objects: {n:,} objects, more than this GL allows")
    assert err.count("\n") == 1 and not (tmp_path / "x.png").exists()
