"""A small progress bar on stderr, for renders that take more than a moment.

No dependency: a bar needs a carriage return and a few characters, not tqdm.  It stays silent
when stderr is not a terminal (a pipe, a log file, CI), and appears only once the work has taken
longer than `Progress.DELAY` seconds, so quick renders print nothing.
"""

from __future__ import annotations

import sys
import time


class Progress:
    """Context manager counting `total` steps:

        with Progress(total=len(tiles), label="render") as bar:
            for tile in tiles:
                ...
                bar.update()

    enabled : True / False, or None (default) for "when stderr is a terminal".
    """

    DELAY = 0.5  # seconds of silence before the bar shows
    INTERVAL = 0.1  # seconds between redraws
    WIDTH = 30  # characters of bar

    def __init__(self, total: int, label: str = "", enabled: bool | None = None, stream=None):
        self.total = max(int(total), 1)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = enabled
        self.done = 0
        self._start = time.monotonic()
        self._last = 0.0
        self._shown = False
        self._drawn = -1

    def __enter__(self) -> "Progress":
        return self

    def update(self, steps: int = 1) -> None:
        self.done = min(self.done + steps, self.total)
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._start < self.DELAY or (now - self._last < self.INTERVAL
                                              and self.done < self.total):
            return
        self._last = now
        self._draw(now)

    def _draw(self, now: float) -> None:
        frac = self.done / self.total
        filled = int(round(frac * self.WIDTH))
        elapsed = now - self._start
        eta = f", {elapsed / frac - elapsed:4.1f} s left" if 0 < frac < 1 else ""
        self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (self.WIDTH - filled)}] "
                          f"{frac:4.0%} {elapsed:5.1f} s{eta}   ")
        self.stream.flush()
        self._shown = True
        self._drawn = self.done

    def __exit__(self, *exc) -> None:
        if self._shown:
            if self._drawn != self.done:
                self._draw(time.monotonic())
            self.stream.write("\n")
            self.stream.flush()
