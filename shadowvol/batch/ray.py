"""Frames made on Ray actors (`pip install 'shadowvol[ray]'`).

Each actor owns one `Worker` (one GL context, one Renderer per scene), made on the thread that
renders, on its first task: a GL context is bound to the thread that made it, and not every
executor calls a class's methods on the thread of its `__init__` (Ray Data's map_batches with a
callable class runs `__call__` on another thread in some Ray versions).  In Ray 2.60 a plain
(max_concurrency=1) actor runs `__init__` and every method on its main thread; the worker
refuses to be called from another thread rather than render on a context it does not hold.

Tasks (runs of frames of one scene) are fed to the actors from a queue, two in flight per actor
(ray.util.ActorPool's scheme, which cannot re-run a dead actor's tasks): when an actor dies its
tasks go back on the queue for the others, and a replacement actor is started, up to
MAX_REPLACEMENTS times in a run.  Actors return bytes; the driver writes the files, so OUT need
be on the driver's machine only.
"""

from __future__ import annotations

import os
import threading
from collections import deque
from collections.abc import Iterator

from shadowvol.batch.worker import Worker, thread_settings
from shadowvol.cli import status
from shadowvol.errors import require

MAX_REPLACEMENTS = 4
IN_FLIGHT_PER_ACTOR = 2


class FrameActor:
    """The actor class (wrapped by ray.remote in `results`)."""

    def __init__(self, scenes: dict, egl_device, environment: dict[str, str], label: str):
        os.environ.update(environment)  # before GL is loaded (the worker loads it lazily)
        self.args = (scenes, egl_device, label)
        self.workers: dict[int, Worker] = {}

    def render(self, task: list[dict]) -> list[dict]:
        thread = threading.get_ident()
        if thread not in self.workers:  # made on the thread that renders
            scenes, egl_device, label = self.args
            self.workers[thread] = Worker(scenes, egl_device, label=label)
        return [self.workers[thread].render(spec) for spec in task]

    def pid(self) -> int:
        return os.getpid()


def results(tasks: list[list[dict]], scenes: dict, actors: int, address: str | None = None,
            egl_device=None, num_gpus: float = 0) -> Iterator[dict]:
    """Render `tasks` on `actors` Ray actors; yields each frame's result as its task ends.
    Uses the Ray this process is connected to, or ray.init(address) and shuts it down after."""
    ray = require("ray", "shadowvol batch --ray", "ray")
    started = not ray.is_initialized()
    if started:
        ray.init(address=address, include_dashboard=False, log_to_driver=True)
    try:
        yield from _run(ray, tasks, scenes, actors, egl_device, num_gpus)
    finally:
        if started:
            ray.shutdown()


def _run(ray, tasks, scenes, actors, egl_device, num_gpus) -> Iterator[dict]:
    pool = _Pool(ray, scenes, actors, egl_device, num_gpus)
    try:
        yield from pool.results(tasks)
    finally:  # free the cluster's CPUs now, not when the handles are collected
        pool.kill()


class _Pool:
    """Actors, a queue of tasks, IN_FLIGHT_PER_ACTOR tasks in flight per actor."""

    def __init__(self, ray, scenes, actors, egl_device, num_gpus):
        self.ray = ray
        self.remote = ray.remote(num_cpus=1, num_gpus=num_gpus)(FrameActor)
        # big Scene objects go to the object store once; an actor holds one CPU of the cluster
        self.args = (ray.put(scenes), egl_device, thread_settings(actors, cores=1))
        self.made = 0
        self.replacements = MAX_REPLACEMENTS
        self.actors = [self._start() for _ in range(max(1, actors))]
        self.queue: deque = deque()
        self.flying: dict = {}  # object ref -> (actor, task)

    def _start(self):
        self.made += 1
        return self.remote.remote(*self.args, f"Ray actor {self.made}")

    def _feed(self) -> None:
        for actor in self.actors:
            while self.queue and sum(a is actor for a, _ in self.flying.values()) < \
                    IN_FLIGHT_PER_ACTOR:
                task = self.queue.popleft()
                self.flying[actor.render.remote(task)] = (actor, task)

    def results(self, tasks) -> Iterator[dict]:
        self.queue.extend(tasks)
        self._feed()
        while self.flying:
            (ref,), _ = self.ray.wait(list(self.flying), num_returns=1)
            actor, task = self.flying.pop(ref)
            try:
                done = self.ray.get(ref)
            except self.ray.exceptions.RayActorError as exc:
                self.queue.appendleft(task)  # made again by another actor
                if any(a is actor for a in self.actors):
                    self.actors = [a for a in self.actors if a is not actor]
                    if self.replacements > 0:
                        self.replacements -= 1
                        self.actors.append(self._start())
                if not self.actors:
                    while self.queue:
                        for spec in self.queue.popleft():
                            yield {"id": spec["id"], "status": status.RENDER_FAILED,
                                   "error": f"every Ray actor died ({type(exc).__name__})"}
                done = []
            yield from done
            self._feed()

    def kill(self) -> None:
        for actor in self.actors:
            self.ray.kill(actor)
