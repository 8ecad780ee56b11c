"""The shadow map's error against the exact shadow, over resolution and bias: the plot of
`shadowvol shadowmap --plot` (the measurements are `shadowvol.compare.shadowmaps`').

Two panels over the map's resolution (256 to 4096 texels a side, log scale), one line per
bias: the pixels the map calls shadowed that are lit (acne, falling as the bias grows) and
those it calls lit that are shadowed (peter-panning, growing with the bias); both fall with
the resolution.  LearnOpenGL's artefacts, counted against the exact shadow.
"""

from __future__ import annotations

import numpy as np

from shadowvol.pictures import figure_pixels

RESOLUTIONS = (256, 512, 1024, 2048, 4096)
BIASES = (0.0005, 0.002, 0.01, 0.1)


def sweep(mapper, resolutions=RESOLUTIONS, biases=BIASES, pcf: int = 1) -> list[dict]:
    """`mapper.measure(...).counts()` for every resolution and bias (a `ShadowMapper`)."""
    return [mapper.measure(n, b, pcf).counts() for b in biases for n in resolutions]


def plot(rows: list[dict], title: str, width: int = 1280, height: int = 560) -> np.ndarray:
    """(height, width, 3) uint8: acne and peter-panning against resolution, a line per bias."""
    from matplotlib.figure import Figure

    dpi = 100
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    fig.suptitle(title)
    biases = sorted({r["bias"] for r in rows})
    for k, (key, what) in enumerate((("acne", "acne: lit, called shadowed"),
                                     ("peter_panning", "peter-panning: shadowed, called lit"))):
        ax = fig.add_subplot(1, 2, k + 1)
        for bias in biases:
            mine = sorted((r for r in rows if r["bias"] == bias), key=lambda r: r["resolution"])
            ax.plot([r["resolution"] for r in mine], [max(r[key], 0.5) for r in mine], "o-",
                    label=f"bias {bias:g}")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("shadow map resolution (texels a side)")
        ax.set_ylabel("pixels wrong (of %d compared)" % rows[0]["pixels"])
        ax.set_title(what)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    return figure_pixels(fig)
