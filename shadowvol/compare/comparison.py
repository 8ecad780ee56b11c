"""Raster against ray traced, side by side and in numbers (`shadowvol compare`).

    from shadowvol.compare import compare
    c = compare(scene)                 # the shadow-volume rasterizer against raytrace
    print(c.table())
    c.exceeds(max_interior=0)          # True when a light has an interior mismatch

Per light it counts the pixels whose `lit` masks differ, the ones among them farther than one
pixel from a mask edge ("interior"; the edge definition is `shadowvol.compare.maskdiff`'s, shared with
the mask tests), and the IoU of the shadow regions (shadow = covered & ~lit); it times both
renderers; and, when asked, measures pyrender's shadow-mapped masks against the ray tracer too
(spot and directional lights only: pyrender has no point-light shadows).

The picture has one row per light — the scene lit by that light alone (and the ambient term) as
the rasterizer draws it, as the ray tracer draws it (direct light only, max_depth 0: exactly
what the rasterizer computes, so only shadows can differ), the masks' difference in the colours
of `maskdiff.LEGEND` and, when asked, pyrender's image — with labels and a legend.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

import raytrace
from raytrace.masks import scene_backend
from raytrace.soft import sample_masks
from shadowvol import pictures
from shadowvol.compare import maskdiff
from shadowvol.compare.pyrender_peer import (
    maskable_lights,
    pyrender_shadow_masks,
    render_pyrender,
)
from shadowvol.io import encode_srgb
from shadowvol.raster.platform.context import create_context
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, DirectionalLight, PointLight, Scene, SpotLight

NOT_ASKED = "not asked"
POINT_LIGHT_NA = "n/a (point light)"


def _kind(light) -> str:
    if isinstance(light, AreaLight):
        return light.shape  # "rect", "disk", "sphere"; its lit mask: every sample reaches
    return {PointLight: "point", DirectionalLight: "directional", SpotLight: "spot"}[type(light)]


@dataclass(frozen=True)
class LightComparison:
    """The numbers of one light.

    index, kind          : position in scene.lights; "point", "directional", "spot" or an
                           area light's shape
    mismatched           : int, pixels whose lit masks differ (raster vs ray tracer)
    interior             : int, of those, the ones farther than one pixel from a mask edge
    iou                  : float, IoU of the shadow regions (1.0 when neither has a shadow)
    pyrender_mismatched  : int or None, pixels where pyrender's lit mask differs from the ray
                           tracer's (None: not asked, or a point light — see pyrender_note)
    pyrender_interior    : int or None, of those, farther than one pixel from an edge
    pyrender_note        : "" when measured, else NOT_ASKED or POINT_LIGHT_NA
    samples              : N, the light's samples (1: not an area light)
    counts_differ, counts_interior, counts_largest : int, an area light's per-sample counts
                           (`maskdiff.count_stats`: pixels whose counts differ, those off every
                           sample edge, the largest difference); None for the other lights
    """

    index: int
    kind: str
    mismatched: int
    interior: int
    iou: float
    pyrender_mismatched: int | None = None
    pyrender_interior: int | None = None
    pyrender_note: str = NOT_ASKED
    samples: int = 1
    counts_differ: int | None = None
    counts_interior: int | None = None
    counts_largest: int | None = None


@dataclass(frozen=True, eq=False)
class Comparison:
    """Everything `compare` measured and drew.

    scene_name, width, height, method : what was compared
    lights            : tuple[LightComparison], in scene order
    coverage_mismatched : int, pixels covered in one renderer only
    times_ms          : dict[str, float]: "raster_setup" (context, upload, shaders), "raster"
                        (one frame, all lights: image and masks), "raytrace" (the reference
                        masks, BVH build included), and "pyrender" (one shadow-mapped frame)
                        when asked
    raster_lit, ref_lit : (L, H, W) bool;  raster_coverage, ref_coverage : (H, W) bool
    raster_images     : (L, H, W, 3) float32 linear RGB, the scene lit by each light alone
    ray_images        : (L, H, W, 3) float64 linear RGB, the same from the ray tracer (direct)
    pyrender_images   : tuple of (H, W, 3) uint8 per light (pyrender's own encoding) or None
                        (not asked, or a point light)
    raster_counts, ref_counts : (L, H, W) uint16, lit_count per light (None: no area light)
    """

    scene_name: str
    width: int
    height: int
    method: str
    lights: tuple[LightComparison, ...]
    coverage_mismatched: int
    times_ms: dict
    raster_lit: np.ndarray = field(repr=False)
    raster_coverage: np.ndarray = field(repr=False)
    ref_lit: np.ndarray = field(repr=False)
    ref_coverage: np.ndarray = field(repr=False)
    raster_images: np.ndarray = field(repr=False)
    ray_images: np.ndarray = field(repr=False)
    pyrender_images: tuple = field(repr=False, default=())
    raster_counts: np.ndarray | None = field(repr=False, default=None)
    ref_counts: np.ndarray | None = field(repr=False, default=None)

    def exceeds(self, max_interior: int) -> bool:
        """True when any light has more than `max_interior` interior mismatches (of its lit
        masks, or of an area light's counts)."""
        return any(l.interior > max_interior or (l.counts_interior or 0) > max_interior
                   for l in self.lights)

    def to_dict(self) -> dict:
        """The numbers, JSON-ready."""
        return {"scene": self.scene_name, "width": self.width, "height": self.height,
                "method": self.method, "coverage_mismatched": self.coverage_mismatched,
                "times_ms": {k: round(v, 3) for k, v in self.times_ms.items()},
                "lights": [{"index": l.index, "kind": l.kind, "mismatched": l.mismatched,
                            "interior": l.interior, "iou": l.iou,
                            "pyrender": ({"mismatched": l.pyrender_mismatched,
                                          "interior": l.pyrender_interior}
                                         if not l.pyrender_note else l.pyrender_note),
                            **({"samples": l.samples,
                                "counts": {"differ": l.counts_differ,
                                           "interior": l.counts_interior,
                                           "largest": l.counts_largest}}
                               if l.counts_differ is not None else {})}
                           for l in self.lights]}

    def table(self) -> str:
        """A text table, one line per light, and the times."""
        asked = any(l.pyrender_note != NOT_ASKED for l in self.lights)
        head = f"{'light':<16} {'mismatched':>10} {'interior':>9} {'shadow IoU':>10}"
        if asked:
            head += f"  {'pyrender wrong (interior)':>25}"
        lines = [f"{self.scene_name} ({self.width}x{self.height}, method {self.method}): "
                 f"raster against ray tracer", head, "-" * len(head)]
        for l in self.lights:
            row = (f"{f'{l.index} ({l.kind})':<16} {l.mismatched:>10} {l.interior:>9} "
                   f"{l.iou:>10.4f}")
            if asked:
                pr = l.pyrender_note or f"{l.pyrender_mismatched} ({l.pyrender_interior})"
                row += f"  {pr:>25}"
            lines.append(row)
            if l.counts_differ is not None:
                lines.append(f"{'':<4}{l.samples} samples: counts differ at {l.counts_differ} "
                             f"px, {l.counts_interior} off sample edges, largest difference "
                             f"{l.counts_largest}")
        if not self.lights:
            lines.append("(no lights)")
        lines.append(f"coverage differs at {self.coverage_mismatched} pixels")
        lines.append("time: " + ", ".join(f"{k} {v:.1f} ms" for k, v in self.times_ms.items()))
        return "\n".join(lines)

    def picture(self) -> np.ndarray:
        """(h, w, 3) uint8 sRGB: a row per light (raster | ray traced | difference [| pyrender]),
        each panel under a label, and the difference colours' legend at the bottom."""
        rows = []
        n = max(len(self.lights), 1)
        for i in range(n):
            if self.lights:
                l = self.lights[i]
                name = f"light {i} ({l.kind})"
                diff = maskdiff.diff_panel(self.raster_lit[i], self.raster_coverage,
                                           self.ref_lit[i], self.ref_coverage)
                diff_label = f"diff: {l.mismatched} px, {l.interior} interior, IoU {l.iou:.4f}"
            else:
                name = "no lights"
                empty = np.zeros((self.height, self.width), bool)
                diff = maskdiff.diff_panel(empty, self.raster_coverage, empty, self.ref_coverage)
                diff_label = f"coverage differs: {self.coverage_mismatched} px"
            panels = [(f"{name}: raster ({self.method})", encode_srgb(self.raster_images[i])),
                      ("ray traced (direct light)", encode_srgb(self.ray_images[i])),
                      (diff_label, diff)]
            if self.pyrender_images:
                image = self.pyrender_images[i] if self.lights else None
                if image is None:
                    note = self.lights[i].pyrender_note if self.lights else POINT_LIGHT_NA
                    panels.append((f"pyrender: {note}", pictures.blank(self.height, self.width, note)))
                else:
                    l = self.lights[i]
                    panels.append((f"pyrender: {l.pyrender_mismatched} px wrong "
                                   f"({l.pyrender_interior} interior)", image))
            rows.append(panels)
            if self.lights and self.lights[i].counts_differ is not None:
                rows.append(self._count_row(i))
        return pictures.legible_rows(rows, maskdiff.LEGEND)

    def _count_row(self, i: int) -> list[tuple[str, np.ndarray]]:
        """An area light's visibility in both renderers and the difference of their counts."""
        l, got, ref = self.lights[i], self.raster_counts[i], self.ref_counts[i]
        return [
            (f"light {i}: raster visibility ({l.samples} samples)",
             maskdiff.visibility_panel(got, l.samples, self.raster_coverage)),
            ("ray traced visibility", maskdiff.visibility_panel(ref, l.samples,
                                                                self.ref_coverage)),
            (f"counts differ: {l.counts_differ} px, {l.counts_interior} off sample edges, "
             f"largest {l.counts_largest}",
             maskdiff.count_diff_panel(got, ref, self.raster_coverage | self.ref_coverage))]


def compare(scene: Scene, method: str = "auto", pyrender: bool = False, *,
            silhouettes: str = "cpu", backend: str = "embree", ctx=None) -> Comparison:
    """Render `scene` with shadow volumes (`method`: "auto", "zpass" or "zfail") and with the
    ray tracer, and compare their masks per light; with `pyrender`, also pyrender's shadow maps.

    ctx : a moderngl context to render in (default: a fresh one).  backend : the ray tracer's
    triangle backend, "embree" or "numpy".
    """

    # One context for the whole comparison, released at the end: pyrender's EGL teardown
    # makes the previously current context current again, so that context must still exist
    # (a Renderer's own context would be gone by then).
    own = ctx is None
    start = time.perf_counter()
    ctx = create_context() if own else ctx
    try:
        return _compare(scene, method, pyrender, silhouettes, backend, ctx, start)
    finally:
        if own:
            ctx.release()


def _compare(scene, method, pyrender, silhouettes, backend, ctx, start) -> Comparison:


    times = {}
    with Renderer(scene, ctx) as renderer:
        times["raster_setup"] = _ms(start)
        renderer.render(method, silhouettes)  # warm-up: lazily built programs and buffers
        start = time.perf_counter()
        result = renderer.render(method, silhouettes)
        times["raster"] = _ms(start)
        lone = [renderer.render(method, silhouettes, lights=(light,)).image
                for light in scene.lights]
        if not lone:
            lone = [result.image]
    start = time.perf_counter()
    ref_lit, ref_cov = raytrace.shadow_masks(scene, backend=backend)
    times["raytrace"] = _ms(start)
    ray_images = [raytrace.render(scene.replace(lights=(light,)), max_depth=0, backend=backend,
                                  progress=False) for light in scene.lights]
    if not ray_images:
        ray_images = [raytrace.render(scene, max_depth=0, backend=backend, progress=False)]

    rows = []
    ref_counts = _reference_counts(scene, backend) if any(
        isinstance(light, AreaLight) for light in scene.lights) else None
    for i, light in enumerate(scene.lights):
        stats = maskdiff.light_stats(result.lit[i], result.coverage, ref_lit[i], ref_cov)
        if isinstance(light, AreaLight):
            count, edges = ref_counts[i]
            stats.update(samples=light.samples, **maskdiff.count_stats(
                result.lit_count[i], result.coverage, count, ref_cov, edges))
        rows.append(LightComparison(i, _kind(light), **stats))
    pr_images = ()
    if pyrender:
        rows, pr_images = _with_pyrender(scene, rows, ref_lit, ref_cov, times)
    return Comparison(
        scene_name=scene.name, width=scene.width, height=scene.height, method=method,
        lights=tuple(rows), coverage_mismatched=int((result.coverage != ref_cov).sum()),
        times_ms=times, raster_lit=result.lit, raster_coverage=result.coverage,
        ref_lit=ref_lit, ref_coverage=ref_cov, raster_images=np.array(lone),
        ray_images=np.array(ray_images), pyrender_images=pr_images,
        raster_counts=None if ref_counts is None else result.lit_count,
        ref_counts=None if ref_counts is None else np.array(
            [ref_counts[i][0] if i in ref_counts else ref_lit[i].astype(np.uint16)
             for i in range(len(scene.lights))]))


def _reference_counts(scene: Scene, backend: str) -> dict:
    """light index -> (lit_count (H, W) uint16, edges (H, W) bool) of every area light: the
    ray tracer's count and the pixels on an edge of some sample's hard mask."""
    mt = scene_backend(scene, backend)
    out = {}
    for i, light in enumerate(scene.lights):
        if isinstance(light, AreaLight):
            count = np.zeros((scene.height, scene.width), np.uint16)
            edges = np.zeros((scene.height, scene.width), bool)
            for _, lit in sample_masks(scene, i, mt):
                count += lit.sum(axis=0, dtype=np.uint16)
                for mask in lit:
                    edges |= maskdiff.edge_pixels(mask)
            out[i] = count, edges
    return out


def _with_pyrender(scene: Scene, rows: list[LightComparison], ref_lit, ref_cov, times):
    """pyrender's numbers and images per light (point lights: POINT_LIGHT_NA, no image)."""

    start = time.perf_counter()
    render_pyrender(scene)
    times["pyrender"] = _ms(start)
    chosen = maskable_lights(scene)
    pr_lit, pr_cov = pyrender_shadow_masks(scene, lights=chosen)
    images = []
    out = []
    for row in rows:
        if row.index not in chosen:
            out.append(replace(row, pyrender_note=POINT_LIGHT_NA))
            images.append(None)
            continue
        k = chosen.index(row.index)
        bad = pr_lit[k] != ref_lit[row.index]
        near = maskdiff.near_edges(pr_lit[k], pr_cov, ref_lit[row.index], ref_cov)
        out.append(replace(row, pyrender_mismatched=int(bad.sum()),
                           pyrender_interior=int((bad & ~near).sum()), pyrender_note=""))
        images.append(render_pyrender(scene.replace(lights=(scene.lights[row.index],))))
    return out, tuple(images)


def _ms(start: float) -> float:
    return (time.perf_counter() - start) * 1e3
