"""One picture of the gallery (a slide) and what the index says about it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class Picture:
    """One picture of the gallery.

    name    : file stem ("cage" -> cage.png)
    title   : the slide's title (drawn into the image) and its entry in the table of contents
    section : the part of the course it belongs to (a key of `gallery.SECTIONS`)
    teaches : the caption: what the picture teaches
    shows   : what is in it, panel by panel
    command : the command that draws it on its own (or the function, when none does)
    image   : (H, W, 3) uint8 sRGB, row 0 at the top, the title strip included
    text    : preformatted text shown under it in the index (the ray tree, a worked
              solution), or ""
    numbers : dict of what the demo counted (e.g. wrong pixels), for the caption and tests
    """

    name: str
    title: str
    section: str
    teaches: str
    shows: str
    command: str
    image: np.ndarray
    text: str = ""
    numbers: dict = field(default_factory=dict)
