"""Frames made on Ray actors (`pip install 'shadowvol[ray]'`).

Each actor owns one `Worker` (one GL context, one Renderer per scene), made on the thread that
renders, on its first task: a GL context is bound to the thread that made it, and not every
executor calls a class's methods on the thread of its `__init__` (Ray Data's map_batches with a
callable class runs `__call__` on another thread in some Ray versions).  In Ray 2.60 a plain
(max_concurrency=1) actor runs `__init__` and every method on its main thread; the worker
refuses to be called from another thread rather than render on a context it does not hold.

Tasks (runs of frames of one scene) are fed to the actors two in flight per actor
(ray.util.ActorPool's scheme, which cannot re-run a dead actor's tasks), each actor from its
own contiguous lane of the frames as in the local pool (`local.lanes`): neighbouring views keep
its Renderer's per-camera caches valid.  When an actor dies its tasks go back to the front of
its lane, and a replacement actor takes the lane over, up to MAX_REPLACEMENTS times in a run
(the others help with the far ends of every lane).  The driver loads each scene once, puts it
in the object store and passes it with an actor's first task of it, so no actor parses mesh
files (a scene that does not load here goes as its path, and the actor records the error).
Actors return bytes; the driver writes the files, so OUT need be on the driver's machine only.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict, deque
from collections.abc import Iterator

from shadowvol import memory
from shadowvol.batch.local import lanes, next_task
from shadowvol.batch.worker import MAX_RENDERERS, Worker, thread_settings
from shadowvol.batch.spec import FrameSpec
from shadowvol.errors import RENDER_FAILED, require
from shadowvol.scene import Scene
from shadowvol.scenefile import load_scene

MAX_REPLACEMENTS = 4
IN_FLIGHT_PER_ACTOR = 2


class FrameActor:
    """The actor class (wrapped by ray.remote in `results`)."""

    def __init__(self, scenes: dict, egl_device, environment: dict[str, str], label: str):
        os.environ.update(environment)  # before GL is loaded (the worker loads it lazily)
        self.args = (scenes, egl_device, label)
        self.workers: dict[int, Worker] = {}

    def render(self, task: list[FrameSpec], scene=None) -> list[dict]:
        """The frames of `task`; `scene` (a Scene or a path, or None when sent before) is the
        scene of its frames."""
        thread = threading.get_ident()
        if thread not in self.workers:  # made on the thread that renders
            scenes, egl_device, label = self.args
            self.workers[thread] = Worker(dict(scenes), egl_device, label=label)
        worker = self.workers[thread]
        if scene is not None:
            worker.scenes[task[0].scene] = scene
        return [worker.render(spec) for spec in task]

    def pid(self) -> int:
        return os.getpid()


def results(tasks: list[list[FrameSpec]], scenes: dict, actors: int, address: str | None = None,
            egl_device=None, num_gpus: float = 0, budget: int | str | None = None
            ) -> Iterator[dict]:
    """Render `tasks` on `actors` Ray actors; yields each frame's result as its task ends.
    Uses the Ray this process is connected to, or ray.init(address) and shuts it down after.
    Each actor's memory budget is `budget` (this machine's default when None) divided by the
    actors: conservative on a cluster, where they do not all share one machine."""
    ray = require("ray", "shadowvol batch --ray", "ray")
    started = not ray.is_initialized()
    if started:
        ray.init(address=address, include_dashboard=False, log_to_driver=True)
    try:
        yield from _run(ray, tasks, scenes, actors, egl_device, num_gpus,
                        memory.budget(budget) // max(1, actors))
    finally:
        if started:
            ray.shutdown()


def _run(ray, tasks, scenes, actors, egl_device, num_gpus, budget: int) -> Iterator[dict]:
    pool = _Pool(ray, scenes, actors, egl_device, num_gpus, budget)
    try:
        yield from pool.results(tasks)
    finally:  # free the cluster's CPUs now, not when the handles are collected
        pool.kill()


class _Pool:
    """Actors, each with its lane of tasks (by slot: a replacement takes the dead actor's),
    IN_FLIGHT_PER_ACTOR tasks in flight per actor."""

    def __init__(self, ray, scenes, actors, egl_device, num_gpus, budget: int):
        self.ray = ray
        self.remote = ray.remote(num_cpus=1, num_gpus=num_gpus)(FrameActor)
        # Scene objects the caller gave go to the object store once; an actor holds one CPU of
        # the cluster
        self.sources = scenes
        self.args = (ray.put({k: v for k, v in scenes.items() if isinstance(v, Scene)}),
                     egl_device, thread_settings(actors, cores=1) | {memory.ENV: str(budget)})
        self.made = 0
        self.replacements = MAX_REPLACEMENTS
        self.actors = [self._start() for _ in range(max(1, actors))]  # None: a dead slot
        self.sent: dict[int, set[str]] = {}   # slot -> the scene keys its actor was sent
        self.kept: OrderedDict = OrderedDict()  # scene key -> object ref (or the path)
        self.lanes: list[deque] = []
        self.flying: dict = {}  # object ref -> (slot, actor, task)

    def _start(self):
        self.made += 1
        return self.remote.remote(*self.args, f"Ray actor {self.made}")

    def _scene(self, key: str):
        source = self.sources[key]
        if isinstance(source, Scene):
            return None   # every actor has it from its constructor
        if key not in self.kept:
            try:
                self.kept[key] = self.ray.put(load_scene(source))
            except Exception:  # noqa: BLE001 - the actor loads it again and records why
                self.kept[key] = source
            while len(self.kept) > MAX_RENDERERS:
                self.kept.popitem(last=False)
        self.kept.move_to_end(key)
        return self.kept[key]

    def _feed(self) -> None:
        for slot, actor in enumerate(self.actors):
            while actor is not None and sum(s == slot for s, _, _ in self.flying.values()) < \
                    IN_FLIGHT_PER_ACTOR:
                task = next_task(self.lanes, slot)
                if task is None:
                    return
                key = task[0].scene
                sent = self.sent.setdefault(slot, set())
                scene = None if key in sent else self._scene(key)
                sent.add(key)
                self.flying[actor.render.remote(task, scene)] = (slot, actor, task)

    def results(self, tasks) -> Iterator[dict]:
        self.lanes = lanes(tasks, len(self.actors))
        self._feed()
        while self.flying:
            (ref,), _ = self.ray.wait(list(self.flying), num_returns=1)
            slot, actor, task = self.flying.pop(ref)
            try:
                done = self.ray.get(ref)
            except self.ray.exceptions.RayActorError as exc:
                self.lanes[slot].appendleft(task)  # made again, by its replacement or another
                if self.actors[slot] is actor:
                    self.sent.pop(slot, None)
                    self.actors[slot] = None
                    if self.replacements > 0:
                        self.replacements -= 1
                        self.actors[slot] = self._start()
                if all(a is None for a in self.actors):
                    for lane in self.lanes:
                        while lane:
                            for spec in lane.popleft():
                                yield {"id": spec.id, "status": RENDER_FAILED,
                                       "error": f"every Ray actor died ({type(exc).__name__})"}
                done = []
            yield from done
            self._feed()

    def kill(self) -> None:
        for actor in self.actors:
            if actor is not None:
                self.ray.kill(actor)
