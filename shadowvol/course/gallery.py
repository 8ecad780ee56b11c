"""The course's gallery: `shadowvol demo -o DIR [--size WxH] [--small]`.

Every demo is a function of the `Gallery` returning one `Picture` (or a list): a slide at the
gallery's size (`slides.Layout`), a caption saying what it teaches, a line saying what it shows,
and the command that draws it on its own.  `build_gallery` runs them all, in the course's order
(`SECTIONS`); only `demo_command` writes files (through `shadowvol.io`): one PNG per picture and
an `index.html` with a table of contents.

    shadowvol demo -o gallery                  # 1920x1080 slides
    shadowvol demo -o gallery --size 1280x720  # any 16:9 (or other) size
    shadowvol demo -o gallery --small          # 480x270 slides (CI)
"""

from __future__ import annotations

import html
import time
from pathlib import Path

from shadowvol import memory
from shadowvol.compare import estimate
from shadowvol.course import (
    demos_outlook,
    demos_tracing,
    demos_volumes,
    shadowmap_plot,
    soft_gallery,
)
from shadowvol.course.picture import Picture
from shadowvol.course.slides import SLIDE, SMALL_SLIDE, SUPERSAMPLE, Layout
from shadowvol.errors import InputError, MissingExtra
from shadowvol.raster.platform.context import create_context
from shadowvol.resources import data_dir
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

__all__ = ["Gallery", "Picture", "build_gallery", "index_html", "DEMOS", "SECTIONS"]

SCENES = data_dir("scenes")  # the installed example scenes, or a source checkout's scenes/
MIN_SIZE = (320, 180)

# The course's order: (key, heading)
SECTIONS = (
    ("shadows", "1. Shadows"),
    ("planar", "2. Planar projected shadows"),
    ("volumes", "3. Shadow volumes"),
    ("stencil", "4. The stencil buffer as a counter"),
    ("zpass", "5. Z-pass and z-fail"),
    ("raytracing", "6. Ray tracing"),
    ("exercises", "7. Exercises"),
    ("outlook", "8. Outlook: checking shadows, and what else one could use"),
    ("gi", "9. Global illumination: the rendering equation and its solutions"),
)

DEMOS = (demos_volumes.cage, soft_gallery.umbra_penumbra, soft_gallery.exact_penumbra,
         soft_gallery.hard_sum,
         demos_volumes.planar, demos_volumes.one_caster,
         demos_volumes.stack_stencil, demos_volumes.counting_side_view,
         demos_volumes.zpass_zfail, demos_tracing.whitted_best, demos_tracing.raytree,
         demos_tracing.tir, demos_tracing.shadow2d, demos_tracing.ray_plane,
         demos_tracing.compare_picture, demos_tracing.shadow_mapping,
         shadowmap_plot.slide) + demos_outlook.DEMOS


def parse_size(text: str) -> tuple[int, int]:
    """"WxH" -> (W, H), each at least MIN_SIZE; InputError (exit 2) otherwise."""
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise InputError("--size", f"{text!r} is not WIDTHxHEIGHT, e.g. 1920x1080") from None
    if w < MIN_SIZE[0] or h < MIN_SIZE[1] or w * h > 8192 * 8192:
        raise InputError("--size", f"{w}x{h} is outside {MIN_SIZE[0]}x{MIN_SIZE[1]} .. "
                                   "8192x8192")
    return w, h


class Gallery:
    """What every demo needs: the scenes folder, the slide layout and one GL context (call
    `release()`)."""

    def __init__(self, small: bool = False, scenes: Path = SCENES, ctx=None,
                 size: tuple[int, int] | None = None):
        self.small = small
        self.size = size or (SMALL_SLIDE if small else SLIDE)
        # --small is for CI: one sample per pixel there
        self.layout = Layout(*self.size, supersample=1 if small else SUPERSAMPLE)
        self.scenes = Path(scenes)
        if not self.scenes.is_dir():
            raise InputError("--scenes", f"no scenes folder at {self.scenes} (pass --scenes DIR)")
        self._own_ctx = ctx is None
        self._ctx = ctx
        self._loaded: dict[str, object] = {}

    @property
    def ctx(self):
        """The GL context the demos draw with, made on first use."""
        if self._ctx is None:
            self._ctx = create_context()
        return self._ctx

    def scene(self, name: str):
        """scenes/<name>.toml (the demos fit it to their panels), read once: a Scene and its
        arrays are immutable."""
        if name not in self._loaded:
            self._loaded[name] = load_scene(self.scenes / f"{name}.toml")
        return self._loaded[name]

    def check_memory(self, limit=None) -> None:
        """Refuse slides whose pictures would not fit the memory budget (`shadowvol.memory`,
        SceneError naming the scene file, exit 2): a slide's largest picture is a scene drawn
        by both renderers at most at the slide's size, so each scene of the folder is
        estimated as `shadowvol compare` of it at that size.  A scene that does not load is
        left to the demo that needs it."""
        budget = memory.budget(limit, "--memory-budget")
        for path in sorted(self.scenes.glob("*.toml")):
            try:
                scene = self.scene(path.stem)
            except SceneError:
                continue
            memory.check(estimate.compare(scene.replace(width=self.size[0],
                                                        height=self.size[1])), budget, str(path))

    def path(self, name: str) -> str:
        """How a command names the scene file: scenes/<name>.toml in a checkout."""
        folder = "scenes" if self.scenes == SCENES else str(self.scenes)
        return f"{folder}/{name}.toml"

    def release(self) -> None:
        if self._own_ctx and self._ctx is not None:
            self._ctx.release()
        self._ctx = None


def build_gallery(small: bool = False, scenes: Path = SCENES, ctx=None, progress=None,
                  size: tuple[int, int] | None = None, skipped: list | None = None,
                  memory_budget=None) -> list[Picture]:
    """Every demo's pictures, in the course's order.  `progress(name, seconds)` is called after
    each demo when given.  A demo needing a missing optional extra (pyrender; scipy for the
    ladder and the caustic) is left out and
    its (name, message) appended to `skipped` when given; otherwise MissingExtra is raised.
    Slides over the memory budget (`memory_budget`, see `Gallery.check_memory`) are refused
    before any demo runs."""
    g = Gallery(small, scenes, ctx, size)
    pictures = []
    try:
        g.check_memory(memory_budget)
        for demo in DEMOS:
            start = time.perf_counter()
            try:
                made = demo(g)
            except MissingExtra as exc:
                if skipped is None:
                    raise
                skipped.append((demo.__name__, str(exc)))
                continue
            pictures += made if isinstance(made, list) else [made]
            if progress:
                progress(demo.__name__, time.perf_counter() - start)
    finally:
        g.release()
    return pictures


# ---------------------------------------------------------------------------------------------
# index.html
# ---------------------------------------------------------------------------------------------

_STYLE = """
body { font-family: sans-serif; max-width: 1280px; margin: 2em auto; padding: 0 1em;
       color: #222; line-height: 1.45; }
nav ol { columns: 2; }
figure { margin: 1.5em 0 3em 0; }
img { display: block; max-width: 100%; height: auto; border: 1px solid #ccc; }
figcaption p { margin: 0.4em 0; }
.shows, .command { color: #555; font-size: 0.92em; }
code { overflow-wrap: anywhere; }
pre { background: #f4f4f4; padding: 0.8em; white-space: pre-wrap; overflow-wrap: anywhere;
      font-size: 0.85em; }
"""


def index_html(pictures: list[Picture], small: bool, size: tuple[int, int] | None = None,
               skipped: list | None = None) -> str:
    """The gallery page: a table of contents in the course's order, then every picture once
    (relative links) with its caption, what it shows and the command that draws it."""
    e = html.escape
    size = size or (SMALL_SLIDE if small else SLIDE)
    flags = " --small" if small else (f" --size {size[0]}x{size[1]}" if size != SLIDE else "")
    by_section = {key: [p for p in pictures if p.section == key] for key, _ in SECTIONS}
    parts = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             "<title>shadowvol: the course gallery</title>", f"<style>{_STYLE}</style>",
             "</head>", "<body>", "<h1>Shadows and ray tracing: the gallery</h1>",
             f"<p>Made by <code>shadowvol demo -o DIR{e(flags)}</code>: {len(pictures)} "
             f"slides of {size[0]}×{size[1]} pixels, in the course's order.  Each says what it "
             "teaches, what it shows and the command that draws it on its own.</p>",
             "<nav><h2>Contents</h2><ol>"]
    for key, heading in SECTIONS:
        if by_section[key]:
            parts.append(f"<li>{e(heading.split('. ', 1)[-1])}<ul>")
            parts += [f'<li><a href="#{e(p.name)}">{e(p.title)}</a></li>'
                      for p in by_section[key]]
            parts.append("</ul></li>")
    parts.append("</ol></nav>")
    for key, heading in SECTIONS:
        if not by_section[key]:
            continue
        parts.append(f'<section id="section-{e(key)}"><h2>{e(heading)}</h2>')
        for p in by_section[key]:
            # the title is in the slide itself; the figure repeats it only as the alt text
            parts += [f'<figure id="{e(p.name)}">',
                      f'<img src="{e(p.name)}.png" alt="{e(p.title)}" '
                      f'width="{p.image.shape[1]}" height="{p.image.shape[0]}">',
                      "<figcaption>", f"<p>{e(p.teaches)}</p>",
                      f'<p class="shows">Shows: {e(p.shows)}.</p>',
                      f'<p class="command">Command: <code>{e(p.command)}</code></p>',
                      "</figcaption>"]
            if p.text:
                parts.append(f"<pre>{e(p.text)}</pre>")
            parts.append("</figure>")
        parts.append("</section>")
    if skipped:
        parts.append("<p>Left out: " + "; ".join(f"{e(n)} ({e(m)})" for n, m in skipped) +
                     "</p>")
    parts += ["</body>", "</html>", ""]
    return "\n".join(parts)
