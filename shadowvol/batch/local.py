"""Frames made on this machine: in this process (one worker), or by a pool of worker processes
started with `spawn` or `forkserver`.

Never `fork` by default: a process forked after its parent made a GL context cannot use EGL
(it would hang; `shadowvol.raster.platform.context` refuses with ForkedContextError), and a batch is
often run from a program that has rendered before.  Each pool process holds one `Worker` (one
context, one Renderer per scene) for its whole life, with llvmpipe's and the BLAS thread counts
set to its share of the cores before GL is loaded.

Two things keep a pool's workers from doing each other's setup again:
- Each worker has its own lane, a contiguous run of the frames; it renders its lane in order and
  then takes tasks from the far end of the longest other lane.  Neighbouring views keep a
  Renderer's per-camera caches valid (a light's stencil-overflow bound is computed once and kept
  while later cameras need no more slack); a round-robin of tasks made workers jump around the
  orbit and compute the bounds again.
- The scenes are loaded here, once, and sent to each worker with its first task of that scene,
  so no worker parses mesh files or imports the mesh library.  A scene that fails to load here
  is sent as its path: the worker records the same error for each of its frames.
"""

from __future__ import annotations

import multiprocessing
import os
import queue
from collections import OrderedDict, deque
from collections.abc import Iterable, Iterator
from multiprocessing.connection import wait

from shadowvol import memory, signals
from shadowvol.batch.worker import MAX_RENDERERS, Worker, thread_settings
from shadowvol.batch.spec import FrameSpec
from shadowvol.errors import RENDER_FAILED
from shadowvol.scene import Scene
from shadowvol.scenefile import load_scene

START_METHODS = ("spawn", "forkserver", "fork")
IN_FLIGHT = 2          # tasks sent ahead to each worker: the one it renders and the next
SHUTDOWN_WAIT_S = 30   # for a worker to release its context after its last task
PARENT_CHECK_S = 1.0   # how often an idle worker looks whether its parent is still there


def in_process(tasks: Iterable[list[FrameSpec]], scenes: dict, egl_device=None,
               budget: int | str | None = None) -> Iterator[dict]:
    """Render every frame of `tasks` here, in order, on one worker (this thread)."""
    worker = Worker(scenes, egl_device, label="in-process worker", budget=budget)
    try:
        for task in tasks:
            for spec in task:
                yield worker.render(spec)
    finally:
        worker.close()


def _serve(tasks, results, egl_device, environment: dict[str, str], label: str) -> None:
    """A pool process: (scenes to add, task) from `tasks` until None; each task's results to
    `results` (its own pipe, so a worker that dies takes no lock with it).  It ends on its own
    when the parent is gone (killed with no chance to stop it)."""
    os.environ.update(environment)  # before GL is loaded: Mesa reads LP_NUM_THREADS then
    signals.keyboard_interrupt()  # a Ctrl-C while the driver links a program: no SIGSEGV
    parent = multiprocessing.parent_process()
    worker = Worker({}, egl_device, label=label)
    try:
        while True:
            try:
                message = tasks.get(timeout=PARENT_CHECK_S)
            except queue.Empty:
                if parent is not None and not parent.is_alive():
                    return
                continue
            if message is None:
                return
            scenes, task = message
            worker.scenes.update(scenes)
            results.send([worker.render(spec) for spec in task])
    except (KeyboardInterrupt, BrokenPipeError):  # Ctrl-C reaches the whole process group
        pass                                      # (the parent reports it), or it is gone
    finally:
        worker.close()


class _Child:
    """One pool process: its task queue, its result pipe, the tasks it holds, the scenes it
    was sent."""

    def __init__(self, context, index: int, egl_device, environment: dict[str, str]):
        self.index = index
        self.tasks = context.Queue()
        self.results, sender = context.Pipe(duplex=False)
        self.process = context.Process(
            target=_serve, name=f"shadowvol-batch-{index}", daemon=True,
            args=(self.tasks, sender, egl_device, environment, f"pool worker {index}"))
        self.process.start()
        sender.close()
        self.flying: deque[list[FrameSpec]] = deque()
        self.scenes: set[str] = set()

    def stop(self, wait_s: float) -> None:
        """Ask it to finish (after what it holds) and wait `wait_s`; then end it."""
        if wait_s > 0 and self.process.is_alive():
            self.tasks.put(None)
            self.process.join(wait_s)
        if self.process.is_alive():
            self.process.terminate()
            self.process.join()
        self.tasks.cancel_join_thread()  # what is left for a dead process stays unsent
        self.tasks.close()
        self.results.close()


class _Scenes:
    """Scenes loaded in this process to send to the workers (the last MAX_RENDERERS kept)."""

    def __init__(self, sources: dict):
        self.sources = sources
        self.kept: OrderedDict[str, Scene] = OrderedDict()

    def get(self, key: str) -> Scene | str:
        source = self.sources[key]
        if isinstance(source, Scene):
            return source
        if key not in self.kept:
            try:
                self.kept[key] = load_scene(source)
            except Exception:  # noqa: BLE001 - the worker loads it again and records why
                return source
            while len(self.kept) > MAX_RENDERERS:
                self.kept.popitem(last=False)
        self.kept.move_to_end(key)
        return self.kept[key]


def lanes(tasks: list[list[FrameSpec]], workers: int) -> list[deque]:
    """Each worker's contiguous run of tasks (nearly equal in number)."""
    n = len(tasks)
    return [deque(tasks[n * w // workers:n * (w + 1) // workers]) for w in range(workers)]


def next_task(runs: list[deque], index: int) -> list[FrameSpec] | None:
    """The next task of worker `index`: the front of its own lane, else the far end of the
    longest lane (the frames farthest from where that lane's worker is); None when all are
    done."""
    if runs[index]:
        return runs[index].popleft()
    donor = max(runs, key=len)
    return donor.pop() if donor else None


def _died(child: _Child) -> list[dict]:
    code = child.process.exitcode
    return [{"id": spec.id, "status": RENDER_FAILED,
             "error": f"a worker process died (exit code {code}) while it held this frame"}
            for task in child.flying for spec in task]


def pool(tasks: list[list[FrameSpec]], scenes: dict, workers: int, egl_device=None,
         start_method: str = "spawn", budget: int | str | None = None) -> Iterator[dict]:
    """Render `tasks` on `workers` processes; yields each frame's result as its task ends.
    A worker that dies fails the frames it held (the next run makes them); the others take
    over the rest of its lane."""
    if start_method not in START_METHODS:
        raise ValueError(f"start_method must be one of {', '.join(START_METHODS)}, got "
                         f"{start_method!r}")
    context = multiprocessing.get_context(start_method)
    count = max(1, min(workers, len(tasks)))
    runs = lanes(tasks, count)
    environment = thread_settings(workers)
    # the workers render at once: each gets its share of the memory budget
    environment[memory.ENV] = str(memory.budget(budget) // count)
    children: list[_Child] = []
    source = _Scenes(scenes)
    finished = False

    def feed(child: _Child) -> None:
        while len(child.flying) < IN_FLIGHT:
            task = next_task(runs, child.index)
            if task is None:
                return
            key = task[0].scene
            sent = {} if key in child.scenes else {key: source.get(key)}
            child.scenes.add(key)
            child.tasks.put((sent, task))
            child.flying.append(task)

    try:
        for i in range(count):
            # a child cut while it is started would be left behind; once in `children` the
            # `finally` below ends it
            with signals.deferred():
                children.append(_Child(context, i, egl_device, environment))
        for child in children:  # they import and start up meanwhile
            feed(child)
        alive = list(children)
        while any(child.flying for child in alive):
            busy = [child for child in alive if child.flying]
            ready = set(wait([c.results for c in busy] + [c.process.sentinel for c in busy]))
            for child in busy:
                if child.results not in ready and child.process.sentinel not in ready:
                    continue
                try:
                    done = child.results.recv() if child.results.poll() else None
                except (EOFError, OSError):
                    done = None
                if done is not None:
                    child.flying.popleft()
                    yield from done
                    feed(child)
                elif not child.process.is_alive():
                    yield from _died(child)
                    child.flying.clear()
                    alive.remove(child)
                    for other in alive:  # they share what is left of its lane
                        feed(other)
        # every worker died: what was never sent fails too
        yield from ({"id": spec.id, "status": RENDER_FAILED,
                     "error": "every worker process died"}
                    for run in runs for task in run for spec in task)
        finished = True
    finally:
        for child in children:
            child.stop(SHUTDOWN_WAIT_S if finished else 0)


def chunks(specs: list[FrameSpec], workers: int, most: int = 8
           ) -> list[list[FrameSpec]]:
    """Tasks for `workers`: runs of consecutive frames of one scene, at most `most` long and
    short enough that every worker gets several (load balance)."""
    size = max(1, min(most, -(-len(specs) // max(1, workers * 4))))
    tasks: list[list[FrameSpec]] = []
    for spec in specs:
        if tasks and len(tasks[-1]) < size and tasks[-1][-1].scene == spec.scene:
            tasks[-1].append(spec)
        else:
            tasks.append([spec])
    return tasks
