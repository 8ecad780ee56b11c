"""The course pictures' titles and panel labels: Pillow's scalable font, sized for full-size
pictures or `--small` ones.  GL-free (the ray-traced pictures use it too)."""

from __future__ import annotations

import numpy as np

from shadowvol import pictures


def strip_height(small: bool) -> int:
    """Height in pixels of a title or label strip."""
    return 16 if small else 30


def text_strip(text: str, width: int, small: bool, *, bold: bool = False) -> np.ndarray:
    """(strip_height, width, 3) uint8: `text` on white (on dark when `bold`), fitted."""
    height = strip_height(small)
    return pictures.text_strip(text, width, height, height - 4 if small else height - 8,
                               dark=bold)


def labelled(panel: np.ndarray, label: str, small: bool) -> np.ndarray:
    """A panel with its label strip above it."""
    return np.concatenate([text_strip(label, panel.shape[1], small), panel])


def titled(image: np.ndarray, title: str, small: bool) -> np.ndarray:
    """The picture with its title strip (dark) on top."""
    return np.concatenate([text_strip(title, image.shape[1], small, bold=True), image])
