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
    remote = ray.remote(num_cpus=1, num_gpus=num_gpus)(FrameActor)
    scenes_ref = ray.put(scenes)  # big Scene objects go to the object store once
    environment = thread_settings(actors, cores=1)  # an actor holds one CPU of the cluster
    made = [0]

    def start():
        made[0] += 1
        return remote.remote(scenes_ref, egl_device, environment, f"Ray actor {made[0]}")

    pool = [start() for _ in range(max(1, actors))]
    queue = deque(tasks)
    flying: dict = {}  # object ref -> (actor, task)
    replacements = MAX_REPLACEMENTS

    def feed(actor) -> None:
        while queue and sum(a is actor for a, _ in flying.values()) < IN_FLIGHT_PER_ACTOR:
            task = queue.popleft()
            flying[actor.render.remote(task)] = (actor, task)

    for actor in pool:
        feed(actor)
    while flying:
        ready, _ = ray.wait(list(flying), num_returns=1)
        ref = ready[0]
        actor, task = flying.pop(ref)
        try:
            done = ray.get(ref)
        except ray.exceptions.RayActorError as exc:
            queue.appendleft(task)  # re-run elsewhere
            if actor in pool:
                pool.remove(actor)
                if replacements > 0:
                    replacements -= 1
                    pool.append(start())
            if not pool:
                failed = list(queue)
                queue.clear()
                for t in failed:
                    for spec in t:
                        yield {"id": spec["id"], "status": status.RENDER_FAILED,
                               "error": f"every Ray actor died ({type(exc).__name__})"}
            for a in pool:
                feed(a)
            continue
        yield from done
        feed(actor)
