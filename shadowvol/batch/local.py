"""Frames made on this machine: in this process (one worker), or by a pool of worker processes
started with `spawn` or `forkserver`.

Never `fork` by default: a process forked after its parent made a GL context cannot use EGL
(it would hang; `shadowvol.raster.context` refuses with ForkedContextError), and a batch is
often run from a program that has rendered before.  Each pool process holds one `Worker` (one
context, one Renderer per scene) for its whole life, with llvmpipe's and the BLAS thread counts
set to its share of the cores before GL is loaded.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool

from shadowvol.batch.worker import Worker, thread_settings
from shadowvol.cli import status

START_METHODS = ("spawn", "forkserver", "fork")


def in_process(tasks: Iterable[list[dict]], scenes: dict, egl_device=None) -> Iterator[dict]:
    """Render every frame of `tasks` here, in order, on one worker (this thread)."""
    worker = Worker(scenes, egl_device, label="in-process worker")
    try:
        for task in tasks:
            for spec in task:
                yield worker.render(spec)
    finally:
        worker.close()


class _Process:
    """The Worker of a pool process (one per process: a process fact, set by `_start`)."""

    worker: Worker | None = None


def _start(scenes: dict, egl_device, environment: dict[str, str]) -> None:
    os.environ.update(environment)  # before GL is loaded: Mesa reads LP_NUM_THREADS then
    _Process.worker = Worker(scenes, egl_device, label="pool worker")


def _render(task: list[dict]) -> list[dict]:
    return [_Process.worker.render(spec) for spec in task]


def pool(tasks: list[list[dict]], scenes: dict, workers: int, egl_device=None,
         start_method: str = "spawn") -> Iterator[dict]:
    """Render `tasks` on `workers` processes; yields each frame's result as its task ends.
    A worker that dies takes its pool down: the frames not yet made are failed frames (the
    next run makes them)."""
    if start_method not in START_METHODS:
        raise ValueError(f"start_method must be one of {', '.join(START_METHODS)}, got "
                         f"{start_method!r}")
    context = multiprocessing.get_context(start_method)
    executor = ProcessPoolExecutor(workers, mp_context=context, initializer=_start,
                                   initargs=(scenes, egl_device, thread_settings(workers)))
    try:
        futures = {executor.submit(_render, task): task for task in tasks}
        for future in as_completed(futures):
            try:
                results = future.result()
            except BrokenProcessPool as exc:
                results = [{"id": spec["id"], "status": status.RENDER_FAILED,
                            "error": f"a worker process died ({exc or 'no reason given'})"}
                           for spec in futures[future]]
            yield from results
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def chunks(specs: list[dict], workers: int, most: int = 8) -> list[list[dict]]:
    """Tasks for `workers`: runs of consecutive frames of one scene, at most `most` long and
    short enough that every worker gets several (load balance)."""
    size = max(1, min(most, -(-len(specs) // max(1, workers * 4))))
    tasks: list[list[dict]] = []
    for spec in specs:
        if tasks and len(tasks[-1]) < size and tasks[-1][-1]["scene"] == spec["scene"]:
            tasks[-1].append(spec)
        else:
            tasks.append([spec])
    return tasks
