"""docs/course.ipynb runs from top to bottom in a fresh kernel, and its frames display
themselves as PNG images; `show` and `_repr_png_` on their own."""

from __future__ import annotations

import io
import os

import nbformat
import numpy as np
import pytest
from builders import ROOT
from nbclient import NotebookClient
from PIL import Image

from shadowvol.display import Panels, picture, show

pytestmark = pytest.mark.gl


def _png(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(data)) as im:
        assert im.format == "PNG"
        return np.asarray(im.convert("RGB"))


def test_the_course_notebook_runs(tmp_path, monkeypatch):
    nb = nbformat.read(ROOT / "docs" / "course.ipynb", as_version=4)
    # the kernel inherits the environment: it imports this checkout
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT),
                                                      os.environ.get("PYTHONPATH", "")]))
    NotebookClient(nb, timeout=240, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.output_type == "error"]
    assert not errors, errors
    images = [o["data"]["image/png"] for c in nb.cells if c.cell_type == "code"
              for o in c.get("outputs", []) if "image/png" in o.get("data", {})]
    assert len(images) >= 6               # the frame itself, then every show(...)
    import base64
    first = _png(base64.b64decode(images[0]))
    assert first.shape == (240, 320, 3) and first.std() > 10     # the cage frame, as rendered
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    assert "λ = (0 − 2.82843) / (-2.82843) = 1" in text and "z-fail 0" in text


def test_frame_displays_as_its_image(ctx):
    from builders import SCENES

    from shadowvol.io import encode_srgb
    from shadowvol.raster.renderer import Renderer
    from shadowvol.scenefile import load_scene
    scene = load_scene(SCENES / "cage.toml").replace(width=40, height=30)
    with Renderer(scene, ctx) as r:
        frame = r.render()
    assert (_png(frame._repr_png_()) == encode_srgb(frame.image)).all()


def test_show_lays_panels_side_by_side():
    rgb = np.zeros((10, 20, 3), np.float32)
    rgb[..., 0] = 1.0
    mask = np.zeros((10, 20), bool)
    mask[:, :5] = True
    counts = np.full((10, 20), 2, np.int16)
    p = show(rgb, mask, counts, labels=["red", "mask", "counts"], height=40)
    assert isinstance(p, Panels)
    img = _png(p._repr_png_())
    assert img.shape[0] == 40 + 28 and img.shape[1] == 3 * 80 + 2 * 4
    assert (img[28 + 5, 5] == (255, 0, 0)).all()                   # the red image, sRGB
    assert (img[28 + 5, 84 + 5] == 255).all() and (img[28 + 5, 84 + 60] == 40).all()
    assert (picture(counts) == picture(counts)[0, 0]).all() and picture(counts)[0, 0].any()
    with pytest.raises(ValueError):
        show(rgb, labels=["a", "b"])
    with pytest.raises(TypeError):
        picture(np.zeros((2, 2, 2)))
