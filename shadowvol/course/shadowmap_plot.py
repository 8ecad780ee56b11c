"""The shadow map's error against the exact shadow, over resolution and bias: the plot of
`shadowvol shadowmap --plot` (the measurements are `shadowvol.compare.shadowmaps`').

Two panels over the map's resolution (256 to 4096 texels a side, log scale), one line per
bias: the pixels the map calls shadowed that are lit (acne, falling as the bias grows) and
those it calls lit that are shadowed (peter-panning, growing with the bias); both fall with
the resolution.  LearnOpenGL's artefacts, counted against the exact shadow.  `slide` is the
gallery's picture of it (the outlook's last word on shadow maps).
"""

from __future__ import annotations

import numpy as np

from shadowvol.compare.shadowmaps import ACNE_COLOUR, PETER_PANNING_COLOUR, ShadowMapper
from shadowvol.course import slides
from shadowvol.course.picture import Picture
from shadowvol.pictures import figure_pixels

RESOLUTIONS = (256, 512, 1024, 2048, 4096)
BIASES = (0.0005, 0.002, 0.01, 0.1)


def sweep(mapper, resolutions=RESOLUTIONS, biases=BIASES, pcf: int = 1) -> list[dict]:
    """`mapper.measure(...).counts()` for every resolution and bias (a `ShadowMapper`)."""
    return [mapper.measure(n, b, pcf).counts() for n in resolutions for b in biases]


def plot(rows: list[dict], title: str, width: int = 1280, height: int = 560,
         text_px: int = 13) -> np.ndarray:
    """(height, width, 3) uint8: acne and peter-panning against resolution, a line per bias;
    its text `text_px` pixels tall."""
    from matplotlib import rc_context
    from matplotlib.figure import Figure

    dpi = 100
    with rc_context({"font.size": text_px * 72 / dpi}):
        fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        _draw(fig, rows, title)
        return figure_pixels(fig)


def _draw(fig, rows: list[dict], title: str) -> None:
    if title:
        fig.suptitle(title)
    biases = sorted({r["bias"] for r in rows})
    for k, (key, what) in enumerate((("acne", "acne"), ("peter_panning", "peter-panning"))):
        ax = fig.add_subplot(1, 2, k + 1)
        for bias in biases:
            mine = sorted((r for r in rows if r["bias"] == bias), key=lambda r: r["resolution"])
            ax.plot([r["resolution"] for r in mine], [max(r[key], 0.5) for r in mine], "o-",
                    label=f"bias {bias:g}")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("shadow map resolution (texels a side)")
        ax.set_ylabel(f"pixels wrong (of {rows[0]['pixels']})")
        ax.set_title(what)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()


SLIDE_BIASES = (0.0005, 0.002, 0.1)


def slide(g) -> Picture:
    """The gallery's slide: the stack's point light shadow-mapped, the pixels it gets wrong
    against the exact shadow, and the error against resolution and bias."""
    L = g.layout
    w, h = L.cell(2, 1, legend=True)
    s = slides.fit(g.scene("stack"), w, h)
    with ShadowMapper(s, 0, g.ctx) as mapper:
        shown = mapper.measure(512, 0.002)
        rows = sweep(mapper, biases=SLIDE_BIASES)
    c = shown.counts()
    at = {(r["bias"], r["resolution"]): r for r in rows}
    diff = shown.picture()[:, -s.width:]          # the difference panel, its label cut off
    diff = diff[-s.height:]
    numbers = {"acne": c["acne"], "peter_panning": c["peter_panning"],
               "wrong_256": at[(0.002, 256)]["misclassified"],
               "wrong_4096": at[(0.002, 4096)]["misclassified"],
               "peter_panning_large_bias": at[(0.1, 4096)]["peter_panning"]}
    title = "Shadow maps against the exact shadow: acne and peter-panning, counted"
    return Picture(
        "shadow_map_error", title, "outlook",
        "A shadow map is only as fine as its texels and needs a bias: too little and lit "
        "surfaces shadow themselves (acne), too much and shadows come loose (peter-panning).  "
        f"Counted against the exact shadow of the shadow volumes: at bias 0.002 the map gets "
        f"{numbers['wrong_256']} pixels wrong at 256 texels a side and "
        f"{numbers['wrong_4096']} at 4096; at bias 0.1 {numbers['peter_panning_large_bias']} "
        "pixels lose their shadow however fine the map.",
        "left: the stack's point light mapped at 512 texels a side, bias 0.002 (acne red, "
        "peter-panning blue); right: the pixels wrong against the map's resolution, a line "
        "per bias",
        f"shadowvol shadowmap {g.path('stack')} -o sm.png --plot plot.png",
        L.compose(title, [[(f"512², bias 0.002: {c['acne']} acne, {c['peter_panning']} "
                            f"peter-panning", _pad(diff, w, h)),
                           ("pixels wrong against resolution",
                            plot(rows, "", w, h, text_px=L.px(22)))]],
                  legend=[("acne: lit, called shadowed", tuple(int(c) for c in ACNE_COLOUR)),
                          ("peter-panning: shadowed, called lit",
                           tuple(int(c) for c in PETER_PANNING_COLOUR))]),
        numbers=numbers)


def _pad(image: np.ndarray, w: int, h: int) -> np.ndarray:
    """`image` padded to (h, w) (the scene fitted to the cell is at most that size)."""
    out = np.zeros((h, w, 3), np.uint8)
    ih, iw = min(h, image.shape[0]), min(w, image.shape[1])
    out[:ih, :iw] = image[:ih, :iw]
    return out
