"""A frame spec: everything that decides one frame of a batch, typed and frozen.

Made in the parent from a checked job alone (`job_frames.specs`), so that every process given it
renders the same frame; it travels to pool processes and Ray actors by pickle.  Its fields are
JSON data (the camera and light tables as the job gave them, checked), and `as_dict` is what
its spec hash is taken of (`job_frames.spec_hash`): the same keys and values as the plain dict a
spec was before it had a type, so the hashes in existing manifests still match.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class FrameSpec:
    """One frame of a job.

    id        : `<job>/<index:06d>`, also its file stem (`job_frames.frame_id`)
    index     : its place in the job, from 0
    job       : the job's name
    scene     : the key of its scene among the run's (a path, or `<Scene id>` for a Scene)
    camera    : {"eye", "target"[, "up", "fov_y", "near"]}: the scene's fill what is left out;
                or {"fx", "fy", "cx", "cy", "camera_to_world"[, "near"]}
    lights    : the job's light tables (the scene-file schema), or None for the scene's
    size      : (width, height), or None for the scene's
    outputs   : the output names (`outputs.OUTPUTS`) it makes, in order
    renderer  : "shadowvol", "raytrace" or "auto" (a row of `sources.SOURCES`)
    method    : the rasterizer's method; max_depth: the ray tracer's recursion depth
    seed, jitter : the job's seed and jitter (`job_frames.jittered`)
    layout    : the dataset layout its files are made as (`layouts.tag`), or None for the job's
                outputs as they are (the files and webdataset layouts); its JSON key is
                "format", as the flag that picks it (`--format`), in every spec hash
    job_index : its job's place in the job file, from 0, for the layouts whose index is of the
                whole dataset (BOP's scene folder; `layouts.tag`), else None
    """

    id: str
    index: int
    job: str
    scene: str
    camera: dict
    lights: tuple | None
    size: tuple[int, int] | None
    outputs: tuple[str, ...]
    renderer: str
    method: str
    max_depth: int
    seed: int
    jitter: dict
    layout: str | None = None
    job_index: int | None = None

    def as_dict(self) -> dict:
        """The spec as JSON data (lists for tuples; no "format" (`layout`) for the plain
        layouts, no "job_index" where it is None)."""
        out = {"id": self.id, "index": self.index, "camera": self.camera, "job": self.job,
               "scene": self.scene, "lights": None if self.lights is None else list(self.lights),
               "size": None if self.size is None else list(self.size),
               "outputs": list(self.outputs), "renderer": self.renderer, "method": self.method,
               "max_depth": self.max_depth, "seed": self.seed, "jitter": self.jitter}
        if self.layout is not None:
            out["format"] = self.layout
        if self.job_index is not None:
            out["job_index"] = self.job_index
        return out
