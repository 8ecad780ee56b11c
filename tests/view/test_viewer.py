"""`shadowvol view` for real: the viewer's window driven by events (keys, drags, the wheel, a
click), screenshot, and the frame's pixels checked against the offscreen (EGL) render of the
same view state.  The window is pyglet's headless EGL one (no X server); one test opens a real X
window under Xvfb (`.ci/run` installs it; without it that test skips, and fails in CI) driven by
X events through the XTEST extension, and checks it does exactly what the headless one does.

The window runs in a child process (its own GLX context; this process keeps the EGL one); the
child writes its screenshots and states, this process renders the same states offscreen."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from builders import ROOT, SCENES, system_program
from PIL import Image

from shadowvol.io import encode_srgb
from shadowvol.raster.planar.draw import PlanarShadows
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import Camera, DirectionalLight
from shadowvol.scenefile import load_scene
from shadowvol.view import picture
from shadowvol.view.app import PANEL_WIDTH
from shadowvol.view.state import ViewState

pytestmark = pytest.mark.gl

SIZE = (240, 180)

# The child: open the viewer, drive it with events, pump pyglet's event loop, record (state,
# screenshot) after each step.  Two drivers send the same steps: "x11" sends real X events
# through XTEST to a window on Xvfb (the window system's own path from device to handler);
# "headless" opens pyglet's headless EGL window (no X server) and dispatches the events that
# pyglet's X11 window would make of them (y from the bottom: height - 1 - row).
CHILD = textwrap.dedent("""
    import ctypes, json, sys, time
    import numpy as np
    from PIL import Image

    scene_path, w, h, out, driver = (sys.argv[1], int(sys.argv[2]), int(sys.argv[3]),
                                     sys.argv[4], sys.argv[5])
    if driver == "headless":
        import pyglet
        pyglet.options["headless"] = True
    from shadowvol.scenefile import load_scene
    from shadowvol.view.app import Viewer

    scene = load_scene(scene_path).replace(width=w, height=h)
    v = Viewer(scene)

    def pump(n=15):
        for _ in range(n):
            v.window.dispatch_events()
            time.sleep(0.01)
        v.draw()
        v.window.flip()

    if driver == "x11":
        v.window.set_location(0, 0)
        x11, xtst = ctypes.CDLL("libX11.so.6"), ctypes.CDLL("libXtst.so.6")
        x11.XOpenDisplay.restype = ctypes.c_void_p
        dpy = ctypes.c_void_p(x11.XOpenDisplay(None))
        x11.XStringToKeysym.restype = ctypes.c_ulong
        x11.XKeysymToKeycode.argtypes = [ctypes.c_void_p, ctypes.c_ulong]

        def move(x, y):
            ox, oy = v.window.get_location()
            xtst.XTestFakeMotionEvent(dpy, -1, ox + x, oy + y, 0)
            x11.XFlush(dpy)
            pump(2)

        def key(name):
            code = x11.XKeysymToKeycode(dpy, x11.XStringToKeysym(name.encode()))
            xtst.XTestFakeKeyEvent(dpy, code, 1, 0)
            xtst.XTestFakeKeyEvent(dpy, code, 0, 0)
            x11.XFlush(dpy)
            pump()

        def button(b, down):
            xtst.XTestFakeButtonEvent(dpy, b, int(down), 0)
            x11.XFlush(dpy)
    else:
        from pyglet.window import key as keys, mouse
        BUTTONS = {1: mouse.LEFT, 2: mouse.MIDDLE, 3: mouse.RIGHT}
        at, held = [0, 0], []

        def move(x, y):
            dx, dy = x - at[0], -(y - at[1])
            at[:] = x, y
            if held:
                v.window.dispatch_event("on_mouse_drag", x, h - 1 - y, dx, dy,
                                        BUTTONS[held[0]], 0)
            pump(2)

        def key(name):
            v.window.dispatch_event("on_key_press", getattr(keys, name.upper()), 0)
            pump()

        def button(b, down):
            x, y = at[0], h - 1 - at[1]
            if b in (4, 5):
                if down:
                    v.window.dispatch_event("on_mouse_scroll", x, y, 0, 1 if b == 4 else -1)
                return
            if down:
                held.append(b)
                v.window.dispatch_event("on_mouse_press", x, y, BUTTONS[b], 0)
            else:
                held.remove(b)
                v.window.dispatch_event("on_mouse_release", x, y, BUTTONS[b], 0)

    def drag(b, x0, y0, x1, y1, steps=6):
        move(x0, y0)
        button(b, True)
        pump(2)
        for k in range(1, steps + 1):
            move(x0 + (x1 - x0) * k // steps, y0 + (y1 - y0) * k // steps)
        button(b, False)
        pump()

    def click(b, x, y):
        move(x, y)
        button(b, True)
        button(b, False)
        pump()

    records = []
    def record(name):
        shot = v.screenshot()
        Image.fromarray(shot).save(f"{out}/{name}.png")
        s = v.state
        records.append({"name": name, "mode": s.mode, "method": s.method,
                        "marker": s.marker, "help": s.help, "probe_light": s.probe_light,
                        "camera": [s.camera.eye.tolist(), s.camera.target.tolist(),
                                   s.camera.up.tolist(), s.camera.fov_y, s.camera.near],
                        "lights": [l.position.tolist() if hasattr(l, "position")
                                   else l.direction.tolist() for l in s.lights],
                        "probe": v.probe_text, "panel": v.panel_lines()})

    pump(30)
    move(w // 2, h // 2)                 # the pointer over the window: it gets the keys
    key("m"); record("start")            # marker off: the bare frame
    key("v"); record("roles")
    key("z"); key("c"); record("zpass_stencil")
    key("n"); key("a"); key("m")
    drag(1, w // 2, h // 2, w // 2 + 40, h // 2 + 10); record("orbit")
    drag(3, w // 2, h // 2, w // 2 - 30, h // 2 + 20); record("light")
    click(4, w // 2, h // 2); record("zoom")
    key("t"); record("raytraced"); key("n")
    click(1, w // 2, h * 3 // 4); record("probe")    # the help still on: the probe readable
    key("h"); record("nohelp")
    json.dump(records, open(f"{out}/records.json", "w"))
    v.close()
    """)
RECORDED = ["start", "roles", "zpass_stencil", "orbit", "light", "zoom", "raytraced"]


def _free_display() -> int:
    for n in range(90, 140):
        if not os.path.exists(f"/tmp/.X11-unix/X{n}") and not os.path.exists(f"/tmp/.X{n}-lock"):
            return n
    pytest.fail("no free X display number")


@pytest.fixture(scope="module")
def xvfb():
    exe = system_program(("Xvfb",), "xvfb")
    n = _free_display()
    proc = subprocess.Popen([exe, f":{n}", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                break
            time.sleep(0.05)
        else:
            pytest.fail("Xvfb did not start")
        yield f":{n}"
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def _drive(driver: str, out, display: str | None = None):
    env = dict(os.environ,
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    env.pop("DISPLAY", None)
    if display is not None:
        env["DISPLAY"] = display
    done = subprocess.run([sys.executable, "-c", CHILD, str(SCENES / "inside_shadow.toml"),
                           str(SIZE[0]), str(SIZE[1]), str(out), driver], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return out, {r["name"]: r for r in json.loads((out / "records.json").read_text())}


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """The viewer on pyglet's headless EGL window: no X server needed."""
    return _drive("headless", tmp_path_factory.mktemp("viewer"))


@pytest.fixture(scope="module")
def x11_session(xvfb, tmp_path_factory):
    """The viewer in a real X window on Xvfb, driven by XTEST events."""
    return _drive("x11", tmp_path_factory.mktemp("viewer-x11"), xvfb)


def state_of(scene, r) -> ViewState:
    eye, target, up, fov, near = r["camera"]
    lights = []
    for light, value in zip(scene.lights, r["lights"]):
        if isinstance(light, DirectionalLight):
            lights.append(DirectionalLight(direction=value, color=light.color,
                                           intensity=light.intensity))
        else:
            lights.append(type(light)(**{**light.__dict__, "position": value}))
    return ViewState(Camera(eye=eye, target=target, up=up, fov_y=fov, near=near),
                     tuple(lights), r["method"], r["mode"], r["marker"], r["help"],
                     r["probe_light"])


def _check_frame(ctx, session, name, tag):
    out, records = session
    scene = load_scene(SCENES / "inside_shadow.toml").replace(width=SIZE[0], height=SIZE[1])
    state = state_of(scene, records[name])
    shot = np.asarray(Image.open(out / f"{name}.png"))
    assert shot.shape == (SIZE[1], SIZE[0] + PANEL_WIDTH, 3)
    with Renderer(scene, ctx) as r, PlanarShadows(r) as p:
        expected = picture.frame(r, state, p)
        if name == "start":           # marker off, shaded: the renderer's image itself
            assert (expected == encode_srgb(r.render().image)).all()
    window = shot[:, :SIZE[0]]
    differ = (window != expected).any(axis=2)
    if differ.any():
        from builders import TEST_OUTPUT
        TEST_OUTPUT.mkdir(exist_ok=True)
        Image.fromarray(np.concatenate([window, expected], axis=1)).save(
            TEST_OUTPUT / f"viewer-{tag}-{name}.png")
    assert not differ.any(), \
        f"{int(differ.sum())} pixels differ (test-output/viewer-{tag}-{name}.png)"


@pytest.mark.parametrize("name", RECORDED)
def test_window_frame_equals_the_offscreen_render(ctx, session, name):
    _check_frame(ctx, session, name, "headless")


def test_the_real_x_window_shows_and_does_what_the_headless_one_does(ctx, x11_session, session):
    """The one test of a real window: X events through the window system give the same states
    and panels as the headless driver, and every frame equals the offscreen render."""
    for name in RECORDED:
        _check_frame(ctx, x11_session, name, "x11")
    timeless = lambda rec: {name: {**r, "panel": [row for row in r["panel"]
                                                  if not row.startswith("frame ")]}
                            for name, r in rec.items()}
    real, headless = timeless(x11_session[1]), timeless(session[1])
    for name in real:
        for key in real[name]:
            assert real[name][key] == headless[name][key], (name, key)


def test_events_changed_the_state(session):
    _, rec = session
    assert rec["start"]["mode"] == "shaded" and rec["start"]["marker"] is False
    assert rec["roles"]["mode"] == "roles"
    assert rec["zpass_stencil"]["method"] == "zpass" and rec["zpass_stencil"]["mode"] == "stencil"
    assert rec["orbit"]["method"] == "auto" and rec["orbit"]["mode"] == "shaded"
    assert rec["orbit"]["camera"][0] != rec["zpass_stencil"]["camera"][0]   # the eye orbited
    assert rec["orbit"]["camera"][1] == rec["zpass_stencil"]["camera"][1]   # about the target
    assert rec["light"]["lights"] != rec["orbit"]["lights"]                 # the light moved
    d = lambda r: np.linalg.norm(np.subtract(r["camera"][0], r["camera"][1]))
    assert d(rec["zoom"]) == pytest.approx(0.9 * d(rec["light"]))           # one wheel step
    assert rec["raytraced"]["mode"] == "raytraced" and rec["probe"]["mode"] == "shaded"
    assert rec["probe"]["help"] is True and rec["nohelp"]["help"] is False


def test_click_probes_the_pixel(session):
    _, rec = session
    text = rec["probe"]["probe"]
    assert text.startswith(f"pixel ({SIZE[0] // 2}, {SIZE[1] * 3 // 4})")
    assert "z-pass sum" in text and "z-fail sum" in text and "stencil read back" in text
    assert "shadow ray to the light crosses" in text
    assert "all counts agree" in text


def test_the_probe_is_readable_the_moment_a_pixel_is_clicked(session):
    """The help is on by default; it never takes the probe's place in the panel: the report
    shows from its first line, as much of it as with the help off."""
    _, rec = session
    with_help, without = rec["probe"]["panel"], rec["nohelp"]["panel"]
    report = rec["probe"]["probe"].splitlines()
    assert report[0].startswith("pixel (") and report[0][:40] in "\n".join(with_help)
    same = lambda rows: [r for r in rows if not r.startswith("frame ")]
    assert same(with_help)[:len(same(without))] == same(without)
    assert len(without) > len(report[:3])


def test_view_without_a_display_is_bad_input(monkeypatch, capsys):
    from shadowvol.cli.main import main
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", str(SCENES / "cage.toml")]) == 2
    assert "no display" in capsys.readouterr().err


def test_view_state_moves():
    from shadowvol.view.state import drag_light, orbit, pan, zoom
    scene = load_scene(SCENES / "cage.toml")
    s = ViewState.of(scene)
    cam = s.camera
    dist = lambda c: np.linalg.norm(c.eye - c.target)
    o = orbit(s, 30, 10).camera
    assert dist(o) == pytest.approx(dist(cam)) and (o.target == cam.target).all()
    assert not np.allclose(o.eye, cam.eye)
    assert dist(zoom(s, 2).camera) == pytest.approx(0.81 * dist(cam))
    p = pan(s, 10, 0, scene.height).camera
    assert np.allclose(p.eye - cam.eye, p.target - cam.target) and not np.allclose(p.eye, cam.eye)
    moved = drag_light(s, 20, 0, scene.height).lights[0]
    delta = moved.position - scene.lights[0].position
    view = cam.target - cam.eye
    assert abs(delta @ view) < 1e-9 * np.linalg.norm(view) and np.linalg.norm(delta) > 0
    assert moved.homogeneous[:3] == pytest.approx(moved.position)     # not the old cache


def test_an_area_light_is_dragged_and_resized():
    from shadowvol.view.app import SIZE_KEYS
    from shadowvol.view.state import RESIZE_PER_STEP, drag_light, resize_light
    scene = load_scene(SCENES / "soft.toml")
    s = ViewState.of(scene)
    light = s.lights[0]
    grown = resize_light(s, SIZE_KEYS["BRACKETRIGHT"]).lights[0]
    np.testing.assert_allclose(grown.size, light.size * RESIZE_PER_STEP)
    assert grown.samples == light.samples and not np.allclose(grown.positions, light.positions)
    # the samples spread with the light: their spread about the centre grows by the same factor
    spread = lambda lt: np.abs(lt.positions - lt.center).max()
    assert spread(grown) == pytest.approx(spread(light) * RESIZE_PER_STEP, rel=0.05)
    shrunk = resize_light(s, SIZE_KEYS["BRACKETLEFT"]).lights[0]
    np.testing.assert_allclose(shrunk.size, light.size / RESIZE_PER_STEP)
    moved = drag_light(s, 40, 0, scene.height).lights[0]
    assert not np.allclose(moved.center, light.center)
    np.testing.assert_allclose(moved.positions - moved.center, light.positions - light.center,
                               atol=1e-12)
    point = ViewState.of(load_scene(SCENES / "cage.toml"))
    assert resize_light(point, 1) is point  # a point light has no size


@pytest.mark.gl
@pytest.mark.parametrize("mode", ["shaded", "roles", "silhouettes", "stencil", "planar",
                                  "exact"])
def test_every_mode_draws_an_area_light_scene(ctx, mode):
    """The counting views take an area light by its centre sample; the shaded view by all."""
    from dataclasses import replace

    from shadowvol.raster.planar.draw import PlanarShadows
    from shadowvol.raster.renderer import Renderer
    from shadowvol.view.picture import frame
    from shadowvol.view.state import hard_view
    scene = load_scene(SCENES / "soft.toml").replace(width=64, height=48)
    s = replace(ViewState.of(scene), mode=mode)
    (centre,) = hard_view(s.lights)
    light = s.lights[0]
    assert np.linalg.norm(centre.position - light.center) == pytest.approx(
        np.linalg.norm(light.positions - light.center, axis=1).min())
    assert centre.intensity == light.intensity
    with Renderer(scene, ctx) as r, PlanarShadows(r) as planar:
        image = frame(r, s, planar)
        assert image.shape == (48, 64, 3) and image.std() > 0
        if mode == "stencil":
            counts = r.render(lights=(centre,), stencil=True).stencil[0]
            assert (counts > 0).any()  # the centre sample's shadow is counted


def test_an_area_light_is_shown_with_few_samples_and_more_on_request():
    from shadowvol.view.app import SAMPLE_KEYS
    from shadowvol.view.state import VIEW_SAMPLES, change_samples
    scene = load_scene(SCENES / "soft.toml")
    s = ViewState.of(scene)
    assert scene.lights[0].samples == 144 and s.lights[0].samples == VIEW_SAMPLES
    more = change_samples(s, SAMPLE_KEYS["PERIOD"])
    assert more.lights[0].samples == 2 * VIEW_SAMPLES
    for _ in range(5):
        more = change_samples(more, SAMPLE_KEYS["PERIOD"])
    assert more.lights[0].samples == 144               # never past the scene's own N
    fewer = s
    for _ in range(8):
        fewer = change_samples(fewer, SAMPLE_KEYS["COMMA"])
    assert fewer.lights[0].samples == 1
    small = scene.replace(lights=(scene.lights[0].__class__(
        "rect", [0.0, 4.0, 0.0], normal=[0.0, -1.0, 0.0], size=[1.0, 1.0], samples=4),))
    assert ViewState.of(small).lights[0].samples == 4  # fewer than VIEW_SAMPLES: kept
