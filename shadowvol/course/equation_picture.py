"""The rendering equation (Kajiya 1986) as a figure: the equation with each term coloured and
named, what it says, and a sketch of the hemisphere at x.  A matplotlib Figure; no backend is
chosen (`shadowvol.pictures.figure_pixels` draws it)."""

from __future__ import annotations

import textwrap

import numpy as np

DPI = 100
COLOURS = {"out": "#202024", "emitted": "#c06000", "integral": "#1e6ee6", "brdf": "#1f9a3e",
           "incoming": "#d62728", "cosine": "#8e44ad"}

# (mathtext, colour key, label or "", where the label goes: "above", "below" or "")
TERMS = (
    (r"$L_o(x,\omega_o)$", "out", "outgoing radiance", "above"),
    (r"$=$", "out", "", ""),
    (r"$L_e(x,\omega_o)$", "emitted", "emitted", "below"),
    (r"$+$", "out", "", ""),
    (r"$\int_{\Omega}$", "integral", "", ""),
    (r"$f_r(x,\omega_i,\omega_o)$", "brdf", "BRDF", "below"),
    (r"$L_i(x,\omega_i)$", "incoming", "incoming radiance", "above"),
    (r"$\cos\theta_i$", "cosine", "cosine", "below"),
    (r"$d\omega_i$", "integral", "", ""),
)
INTEGRAL_LABEL = r"the integral over the hemisphere $\Omega$ of directions $\omega_i$ above x"

LINES = (
    r"Kajiya 1986: the radiance leaving x toward $\omega_o$ is what x emits, plus all it "
    r"reflects of the light arriving from every direction $\omega_i$ of the hemisphere "
    r"$\Omega$ above x: the BRDF $f_r$ weighs each direction, the cosine spreads the light "
    "over the surface.",
    r"The coupling: $L_i(x,\omega_i) = L_o(x',-\omega_i)$ is what leaves x', the nearest "
    r"surface x sees along $\omega_i$ (the visibility V).  Every surface lights every other "
    "one: L solves an integral equation.",
    "Solving it: local illumination drops all the coupling; Whitted keeps it for mirrors and "
    "glass, radiosity for diffuse surfaces; Monte Carlo (path tracing, photon maps) keeps all "
    "of it.",
)


def _place(fig, renderer, y_px: float, size_px: float) -> list:
    """Draw `TERMS` in a row centred at height `y_px` (pixels from the bottom); returns each
    term's window extent (pixels)."""
    W = fig.bbox.width
    pt = size_px * 72 / DPI
    gap = 0.25 * size_px
    texts = [fig.text(0, y_px / fig.bbox.height, tex, fontsize=pt, color=COLOURS[c],
                      va="baseline", ha="left") for tex, c, _, _ in TERMS]
    widths = [t.get_window_extent(renderer).width for t in texts]
    x = (W - sum(widths) - gap * (len(texts) - 1)) / 2
    for t, w in zip(texts, widths):
        t.set_x(x / W)
        x += w + gap
    return [t.get_window_extent(renderer) for t in texts]


def _bracket(fig, x0, x1, y, tick, colour, lw) -> None:
    """A square bracket from x0 to x1 at height y (pixels), its ends bent by `tick`."""
    from matplotlib.lines import Line2D

    W, H = fig.bbox.width, fig.bbox.height
    xs, ys = np.array([x0, x0, x1, x1]) / W, np.array([y - tick, y, y, y - tick]) / H
    fig.add_artist(Line2D(xs, ys, color=colour, lw=lw, transform=fig.transFigure))


def _labels(fig, boxes, label_px: float) -> float:
    """Each labelled term's bracket and name, above or below it; the integral's bracket
    under all of it.  Returns the lowest pixel height used."""
    W, H = fig.bbox.width, fig.bbox.height
    pt, pad, lw = label_px * 72 / DPI, 0.35 * label_px, label_px / 10
    top = max(b.y1 for b in boxes) + pad
    bottom = min(b.y0 for b in boxes) - pad
    for (_, c, label, where), b in zip(TERMS, boxes):
        if not label:
            continue
        y, tick = (top, -pad) if where == "above" else (bottom, pad)
        _bracket(fig, b.x0 + 2, b.x1 - 2, y, tick, COLOURS[c], lw)
        fig.text((b.x0 + b.x1) / 2 / W, (y - tick * 0.6) / H, label, fontsize=pt,
                 color=COLOURS[c], ha="center", va="bottom" if where == "above" else "top")
    first = next(b for (_, c, _, _), b in zip(TERMS, boxes) if c == "integral")
    last = boxes[-1]
    y = bottom - 2.4 * label_px
    _bracket(fig, first.x0, last.x1, y, 1.2 * pad, COLOURS["integral"], lw)
    fig.text((first.x0 + last.x1) / 2 / W, (y - 0.6 * pad) / H, INTEGRAL_LABEL, fontsize=pt,
             color=COLOURS["integral"], ha="center", va="top")
    return y - 1.8 * label_px


def _hemisphere(ax, text_px: float) -> None:
    """The sketch: the surface at x, the hemisphere, the normal, the incoming direction
    toward the surface x' it sees, the outgoing one toward the eye, the angle and the
    BRDF's lobe."""
    pt, lw = text_px * 72 / DPI, text_px / 9
    arrow = dict(arrowstyle="-|>", lw=lw, mutation_scale=text_px)
    ax.plot([-1.35, 1.35], [0, 0], color="#444444", lw=lw * 1.5)
    a = np.linspace(0, np.pi, 100)
    ax.plot(np.cos(a), np.sin(a), color=COLOURS["integral"], lw=lw, ls="--")
    ax.text(1.0, 0.22, r"$\Omega$", color=COLOURS["integral"], fontsize=pt * 1.2)
    ax.annotate("", (0, 1.05), (0, 0), arrowprops=dict(arrow, color="#444444"))
    ax.text(0.05, 1.08, "n", fontsize=pt)
    wi = np.array([-np.sin(np.radians(50)), np.cos(np.radians(50))])
    far = 1.55 * wi
    ax.plot(*np.array([far - 0.3 * np.array([wi[1], -wi[0]]),
                       far + 0.3 * np.array([wi[1], -wi[0]])]).T, color="#444444", lw=lw * 2)
    ax.text(*(far + np.array([-0.1, 0.12])), "x'", fontsize=pt, ha="right")
    ax.annotate("", (0, 0), far, arrowprops=dict(arrow, color=COLOURS["incoming"]))
    ax.text(*(0.72 * wi + np.array([-0.32, -0.02])), r"$\omega_i$", color=COLOURS["incoming"],
            fontsize=pt)
    wo = np.array([np.sin(np.radians(40)), np.cos(np.radians(40))])
    ax.annotate("", 1.2 * wo, (0, 0), arrowprops=dict(arrow, color=COLOURS["out"]))
    ax.text(*(1.22 * wo + np.array([0.04, 0.0])), r"$\omega_o$ (to the eye)", fontsize=pt)
    t = np.linspace(np.pi / 2, np.pi / 2 + np.radians(50), 30)
    ax.plot(0.38 * np.cos(t), 0.38 * np.sin(t), color=COLOURS["cosine"], lw=lw)
    ax.text(-0.2, 0.45, r"$\theta_i$", color=COLOURS["cosine"], fontsize=pt, ha="right")
    lobe = np.linspace(-np.pi / 2, np.pi / 2, 100)
    r = 0.55 * np.cos(lobe) ** 6
    mirror = np.arctan2(wi[1], -wi[0])
    ax.plot(r * np.cos(mirror + lobe), r * np.sin(mirror + lobe), color=COLOURS["brdf"],
            lw=lw)
    ax.text(0.0, -0.2, "x", fontsize=pt, ha="center", va="top")
    ax.set_xlim(-1.45, 1.95), ax.set_ylim(-0.4, 1.9), ax.set_aspect("equal")
    ax.axis("off")


def equation_figure(width_px: int, height_px: int, text_px: float = 32):
    """The slide's body: the equation (its terms at twice `text_px`), each term named, what it
    says underneath and the hemisphere sketched at the right."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_px / DPI, height_px / DPI), dpi=DPI)
    renderer = FigureCanvasAgg(fig).get_renderer()
    boxes = _place(fig, renderer, height_px - 4.8 * text_px, 2.0 * text_px)
    low = _labels(fig, boxes, text_px)
    split = 0.58  # the text's share of the width, the sketch has the rest
    chars = int(split * width_px / (0.52 * text_px))
    y = low - text_px
    for line in LINES:
        wrapped = textwrap.wrap(line, chars)
        # mathtext must stay on one line: join what the wrap split inside $...$
        joined, cur = [], ""
        for part in wrapped:
            cur = f"{cur} {part}" if cur else part
            if cur.count("$") % 2 == 0:
                joined.append(cur)
                cur = ""
        for part in joined + ([cur] if cur else []):
            fig.text(0.02, y / height_px, part, fontsize=text_px * 72 / DPI, va="top")
            y -= 1.45 * text_px
        y -= 0.6 * text_px
    ax = fig.add_axes([split + 0.02, 0.02, 1 - split - 0.04, max(0.1, low / height_px - 0.04)])
    _hemisphere(ax, text_px)
    return fig
