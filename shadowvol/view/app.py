"""The interactive viewer: a pyglet window showing a scene's shadow volumes, live.

pyglet (not moderngl-window): it is already installed with pyrender, it is what
moderngl-window itself wraps on Linux, and the viewer needs only a window, a GL 4.5 context and
its events; moderngl-window would add a dependency and its own render loop for nothing more.

The window's left part is the frame of the current `ViewState` (`picture.frame`, rendered by a
`Renderer` in the window's own GL context, blitted one texel per pixel: the same pixels as an
offscreen render of that state); the right part is a side panel with the state, the keys and
the count probe's report.

    mouse   left drag: orbit    shift+left or middle drag: pan    wheel: zoom
            right drag: move the light    left click: probe the pixel
    keys    A auto  Z z-pass  F z-fail   (counting method)
            N shaded  V volumes by role  S silhouettes  C stencil counts  P planar
            T raster beside ray traced (split screen)
            L next light   M light marker   H help   Esc quit
"""

from __future__ import annotations

import textwrap
import time
from dataclasses import replace

import numpy as np
from PIL import Image, ImageDraw

from shadowvol.course.probe import probe
from shadowvol.errors import MissingExtra, require
from shadowvol.raster.planar.draw import PlanarShadows, ReceiverError, receiver_index
from shadowvol.raster.platform import window
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import SceneError
from shadowvol.view import picture
from shadowvol.view.state import (
    ViewState,
    change_samples,
    drag_light,
    hard_view,
    orbit,
    pan,
    resize_light,
    zoom,
)

PANEL_WIDTH = 520          # pixels of the side panel
PANEL_TEXT_PX = 13
CLICK_SLOP = 3             # a press and release this close (pixels, no drag) is a click

HELP = """mouse
  left drag      orbit
  shift+left     pan (or middle drag)
  wheel          zoom
  right drag     move the light
  left click     probe the pixel
keys
  A / Z / F      auto / z-pass / z-fail
  N              shaded
  V              shadow volumes by role
  S              silhouette edges
  C              stencil counts (heat map)
  P              planar projected shadows
  T              raster | ray traced, split (slow)
  E              sampled | exact area light, split
  L              next light
  [ / ]          shrink / grow an area light
  , / .          halve / double its samples
  M              light marker on/off
  H              this help on/off
  Esc            quit"""

MODE_KEYS = {"N": "shaded", "V": "roles", "S": "silhouettes", "C": "stencil", "P": "planar",
             "T": "raytraced", "E": "exact"}
METHOD_KEYS = {"A": "auto", "Z": "zpass", "F": "zfail"}
SIZE_KEYS = {"BRACKETLEFT": -1, "BRACKETRIGHT": 1}  # area light: shrink, grow
SAMPLE_KEYS = {"COMMA": 0.5, "PERIOD": 2.0}          # area light: halve, double its samples


def _mono(px: int):
    """DejaVu Sans Mono (shipped with matplotlib): the panel's columns line up."""
    from matplotlib import font_manager
    from PIL import ImageFont

    return ImageFont.truetype(font_manager.findfont(
        font_manager.FontProperties(family="DejaVu Sans Mono")), px)


class Viewer:
    """A window on `scene` (call `close()`).  `visible=False` for tests and benchmarks, or
    pyglet's headless EGL window (`pyglet.options["headless"] = True` before the first viewer):
    no X server needed."""

    def __init__(self, scene, visible: bool = True):
        pyglet = require("pyglet", "the interactive viewer (shadowvol view)", extra="view")
        self.pyglet = pyglet
        self.scene = scene
        # 8 bits a channel asked for: a config left to choose may be 16-bit (565), and the
        # window would then not show the frame's own pixels
        config = pyglet.gl.Config(major_version=4, minor_version=5, forward_compatible=True,
                                  double_buffer=True, depth_size=24, red_size=8, green_size=8,
                                  blue_size=8)
        self.window = pyglet.window.Window(scene.width + PANEL_WIDTH, scene.height,
                                           caption=f"shadowvol view: {scene.name}",
                                           config=config, visible=visible, resizable=False)
        self.window.switch_to()
        self.ctx = window.attach(egl=bool(pyglet.options["headless"]))
        self.renderer = Renderer(scene, self.ctx)
        try:
            receiver_index(scene)
            self.planar = PlanarShadows(self.renderer)
        except ReceiverError:
            self.planar = None      # no plane to project onto: the P key says so
        self.blit = window.Blit(self.ctx)
        self.state = ViewState.of(scene)
        self.message = ""
        self.probe_text = "left click a pixel to probe it"
        self.frame_ms = 0.0
        self._frame = None
        self._press = None
        self._moved = False
        self.window.push_handlers(self.on_draw, self.on_key_press, self.on_mouse_press,
                                  self.on_mouse_drag, self.on_mouse_release,
                                  self.on_mouse_scroll)

    # -- drawing -------------------------------------------------------------------------
    def set_state(self, state: ViewState) -> None:
        if state != self.state:
            self.state = state
            self._frame = None

    def frame(self) -> np.ndarray:
        """(H, W, 3) uint8: the current state's frame (rendered again only after a change)."""
        if self._frame is None:
            start = time.perf_counter()
            self._frame = picture.frame(self.renderer, self.state, self.planar)
            self.frame_ms = (time.perf_counter() - start) * 1e3
        return self._frame

    def picture(self) -> np.ndarray:
        """(H, W + PANEL_WIDTH, 3) uint8: the frame and the side panel."""
        return np.concatenate([self.frame(), self.panel()], axis=1)

    def panel_lines(self) -> list[str]:
        """The side panel's text as drawn, the lines that fit: the state, then the probe's
        report (so a click is readable at once, help on or off), then the help."""
        s = self.state
        lights = ", ".join(f"{i}: {type(l).__name__.replace('Light', '').lower()}"
                           for i, l in enumerate(s.lights)) or "none"
        head = [f"{self.scene.name}: {s.mode}, {s.method}",
                f"lights {lights}; probing light {s.probe_light}",
                f"frame {self.frame_ms:.0f} ms ({1e3 / max(self.frame_ms, 1e-3):.0f} fps)"]
        if self.message:
            head.append(self.message)
        body = HELP.splitlines() if s.help else []
        columns = max(20, int((PANEL_WIDTH - 16) / _mono(PANEL_TEXT_PX).getlength("m")))
        lines = []
        for line in head + [""] + self.probe_text.splitlines() + [""] + body:
            lines += textwrap.wrap(line, columns, subsequent_indent="    ",
                                   drop_whitespace=False) or [""]
        fit = max(0, (self.scene.height - 6) // self._line_step())
        return lines[:fit]

    @staticmethod
    def _line_step() -> int:
        return round(PANEL_TEXT_PX * 1.3)

    def panel(self) -> np.ndarray:
        img = Image.new("RGB", (PANEL_WIDTH, self.scene.height), (250, 250, 250))
        draw = ImageDraw.Draw(img)
        f = _mono(PANEL_TEXT_PX)
        for i, line in enumerate(self.panel_lines()):
            draw.text((8, 6 + i * self._line_step()), line, fill=(20, 20, 24), font=f)
        return np.asarray(img, np.uint8)

    def draw(self) -> None:
        self.window.switch_to()
        self.blit.show(self.picture())

    def on_draw(self):
        self.draw()
        return True    # handled: pyglet's default clear would erase it

    def screenshot(self) -> np.ndarray:
        """(H, W + PANEL_WIDTH, 3) uint8: what the window's back buffer holds now."""
        self.window.switch_to()
        return self.blit.read_window(self.scene.width + PANEL_WIDTH, self.scene.height)

    # -- events ----------------------------------------------------------------------------
    def on_key_press(self, symbol, modifiers):
        key = self.pyglet.window.key
        name = key.symbol_string(symbol)
        s = self.state
        self.message = ""
        if name in METHOD_KEYS:
            self.set_state(replace(s, method=METHOD_KEYS[name]))
        elif name in MODE_KEYS:
            mode = MODE_KEYS[name]
            if mode == "planar" and self.planar is None:
                self.message = "no plane object: no planar shadows"
            elif mode == "exact" and self.no_exact():
                self.message = self.no_exact()
            else:
                self.set_state(replace(s, mode=mode))
        elif name == "M":
            self.set_state(replace(s, marker=not s.marker))
        elif name == "H":
            self.state = replace(s, help=not s.help)        # the panel only
        elif name in SIZE_KEYS:
            self.set_state(resize_light(s, SIZE_KEYS[name]))
        elif name in SAMPLE_KEYS:
            self.set_state(change_samples(s, SAMPLE_KEYS[name]))
        elif name == "L" and s.lights:
            self.set_state(replace(s, probe_light=(s.probe_light + 1) % len(s.lights)))
        elif symbol == key.ESCAPE:
            return False                                     # pyglet's default: close
        return True

    def no_exact(self) -> str:
        """Why the exact mode cannot draw this scene ("" when it can): a sphere light, or no
        shapely."""
        from raytrace.exact_soft import check_exact
        try:
            check_exact(self.scene)
        except (SceneError, MissingExtra) as exc:
            return f"no exact view: {exc}"
        return ""

    def on_mouse_press(self, x, y, button, modifiers):
        self._press = (x, y)
        self._moved = False

    def on_mouse_drag(self, x, y, dx, dy, buttons, modifiers):
        mouse, key = self.pyglet.window.mouse, self.pyglet.window.key
        if self._press and max(abs(x - self._press[0]), abs(y - self._press[1])) > CLICK_SLOP:
            self._moved = True
        h = self.scene.height
        if buttons & mouse.RIGHT:
            self.set_state(drag_light(self.state, dx, dy, h))
        elif buttons & mouse.MIDDLE or (buttons & mouse.LEFT and modifiers & key.MOD_SHIFT):
            self.set_state(pan(self.state, dx, dy, h))
        elif buttons & mouse.LEFT:
            self.set_state(orbit(self.state, dx, dy))

    def on_mouse_release(self, x, y, button, modifiers):
        if (button == self.pyglet.window.mouse.LEFT and not self._moved
                and 0 <= x < self.scene.width and 0 <= y < self.scene.height):
            self.probe_pixel(int(x), self.scene.height - 1 - int(y))
        self._press = None

    def on_mouse_scroll(self, x, y, scroll_x, scroll_y):
        self.set_state(zoom(self.state, scroll_y))

    def probe_pixel(self, px: int, py: int):
        """Probe pixel (px, py) (row 0 at the top) for the current state; the report goes
        to the side panel and is returned."""
        s = self.state
        if not s.lights:
            self.probe_text = "no lights: nothing to probe"
            return None
        p = probe(self.renderer, px, py, s.probe_light, s.method, camera=s.camera,
                  lights=hard_view(s.lights))  # an area light: its centre sample
        self.probe_text = p.explain([o.name for o in self.scene.objects])
        print(self.probe_text, flush=True)
        return p

    # -- running ---------------------------------------------------------------------------
    def run(self) -> None:
        self.pyglet.app.run()

    def close(self) -> None:
        self.window.switch_to()
        if self.planar is not None:
            self.planar.release()
        self.renderer.release()
        self.blit.release()
        self.window.close()
