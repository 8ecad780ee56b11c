"""A frame the GL cannot allocate is one clear error (exit 3), not "framebuffer incomplete"."""

from __future__ import annotations

import moderngl
import pytest
from builders import SCENES

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.raster import target as target_module
from shadowvol.raster.gl import RawGL
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
