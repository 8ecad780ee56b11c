"""`shadowvol view`'s exact mode (key E): the area light's sampled frame (left half) beside
the ray tracer's exact one (right half, `raytrace.outlook.analytic`: no sample noise), in the
viewer's window driven by its key, screenshot and checked against the offscreen render of the
same state; a scene with a sphere light keeps its mode and says why in the panel.  As in
tests/course/test_viewer.py, the window is pyglet's headless EGL one, in a child process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from dataclasses import replace

import numpy as np
import pytest
from builders import ROOT, SCENES
from PIL import Image

from shadowvol.io import encode_srgb
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight
from shadowvol.scenefile import load_scene
from shadowvol.view import picture
from shadowvol.view.app import PANEL_WIDTH
from shadowvol.view.state import ViewState

pytestmark = pytest.mark.gl
pytest.importorskip("pyglet", reason="the viewer needs pyglet: pip install 'shadowvol[view]'")
pytest.importorskip("shapely", reason="the exact view needs shapely: "
                                      "pip install 'shadowvol[exact]'")

SIZE = (96, 120)  # tall enough for the panel to show the message

CHILD = textwrap.dedent("""
    import json, sys, time
    import numpy as np
    import pyglet
    pyglet.options["headless"] = True
    from PIL import Image
    from shadowvol.scene import AreaLight
    from shadowvol.scenefile import load_scene
    from shadowvol.view.app import Viewer

    path, w, h, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
    scene = load_scene(path).replace(width=w, height=h)
    records = {}
    for name, sc in (("soft", scene),
                     ("sphere", scene.replace(lights=(AreaLight("sphere", [0, 4, 0],
                                                                radius=0.5, samples=4),)))):
        v = Viewer(sc)
        for _ in range(10):
            v.window.dispatch_events()
        v.on_key_press(pyglet.window.key.M, 0)      # the marker off: the bare frames
        v.on_key_press(pyglet.window.key.E, 0)
        v.draw()
        v.window.flip()
        Image.fromarray(v.screenshot()).save(f"{out}/{name}.png")
        records[name] = {"mode": v.state.mode, "marker": v.state.marker,
                         "message": v.message, "panel": v.panel_lines()}
        v.close()
    json.dump(records, open(f"{out}/records.json", "w"))
    """)


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    out = tmp_path_factory.mktemp("viewer-exact")
    env = dict(os.environ,
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    env.pop("DISPLAY", None)
    done = subprocess.run([sys.executable, "-c", CHILD, str(SCENES / "soft.toml"),
                           str(SIZE[0]), str(SIZE[1]), str(out)], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return out, json.loads((out / "records.json").read_text())


def test_the_key_shows_the_exact_frame_beside_the_sampled_one(ctx, session):
    out, records = session
    assert records["soft"]["mode"] == "exact" and not records["soft"]["marker"]
    assert records["soft"]["panel"][0].endswith("exact, auto")
    scene = load_scene(SCENES / "soft.toml").replace(width=SIZE[0], height=SIZE[1])
    state = replace(ViewState.of(scene), mode="exact", marker=False)
    with Renderer(scene, ctx) as r:
        expected = picture.frame(r, state)
        sampled = encode_srgb(r.render(lights=state.lights).image)
    shot = np.asarray(Image.open(out / "soft.png"))
    assert shot.shape == (SIZE[1], SIZE[0] + PANEL_WIDTH, 3)
    assert (shot[:, :SIZE[0]] == expected).all()
    # the right half is the analytic image of the scene with the view's lights, the left the
    # raster's sampled frame (below the labels' strip)
    exact = picture.exact_image(scene.replace(lights=state.lights))
    half, below = SIZE[0] // 2, 24  # under the labels
    assert (expected[below:, half + 1:] == exact[below:, half + 1:]).all()
    assert (expected[below:, :half - 1] == sampled[below:, :half - 1]).all()
    # and they differ: the exact penumbra has no sample noise
    assert (exact != sampled).any(axis=2).sum() > 50


def test_a_sphere_light_keeps_the_mode_and_says_why(session):
    _, records = session
    rec = records["sphere"]
    assert rec["mode"] == "shaded"
    assert rec["message"].startswith("no exact view:") and "sphere" in rec["message"]
    assert any("no exact view" in line for line in rec["panel"])
