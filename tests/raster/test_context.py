"""The context factory's errors, and the raw-GL state a frame leaves behind."""

from __future__ import annotations

import moderngl
import pytest
from builders import tiny_scene

from shadowvol.raster.platform import context
from shadowvol.raster.platform.gl import GL_CLIP_DEPTH_MODE, GL_DEPTH_CLAMP, GL_STENCIL_TEST, RawGL
from shadowvol.raster.renderer import Renderer


def test_missing_egl_names_what_to_install(monkeypatch):
    def fail(**kwargs):
        raise Exception("libEGL.so.1: cannot open shared object file")

    monkeypatch.setattr(moderngl, "create_context", fail)
    with pytest.raises(context.ContextError) as err:
        context.create_context()
    assert "libegl1" in str(err.value) and "libgl1-mesa-dri" in str(err.value)
    assert "libEGL.so.1" in str(err.value)


def test_too_old_gl_names_the_version(monkeypatch):
    class Old:
        version_code = 330
        info = {"GL_VERSION": "3.3 (Core Profile) Mesa"}
        released = False

        def release(self):
            Old.released = True

    monkeypatch.setattr(moderngl, "create_context", lambda **kw: Old())
    with pytest.raises(context.ContextError, match=r"3\.3.*needs 4\.5"):
        context.create_context()
    assert Old.released


def test_a_frame_restores_the_raw_gl_state(ctx):
    gl = RawGL()
    before = (gl.glIsEnabled(GL_STENCIL_TEST), gl.glIsEnabled(GL_DEPTH_CLAMP),
              gl.get_int(GL_CLIP_DEPTH_MODE), gl.get_int(0x0B98))  # STENCIL_WRITEMASK
    with Renderer(tiny_scene(), ctx) as r:
        r.render("zfail", stencil=True)
        r.volume_view("zfail")
    after = (gl.glIsEnabled(GL_STENCIL_TEST), gl.glIsEnabled(GL_DEPTH_CLAMP),
             gl.get_int(GL_CLIP_DEPTH_MODE), gl.get_int(0x0B98))
    assert after == before
    assert before[:3] == (0, 0, 0x935E)  # GL defaults: off, off, NEGATIVE_ONE_TO_ONE
