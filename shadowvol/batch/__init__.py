"""Datasets at scale: `shadowvol batch` / `shadowvol.batch.run(jobs, out, ...)`.

    import shadowvol.batch
    summary = shadowvol.batch.run("scenes/turntable.jsonl", "out", workers=2)

Jobs (`jobs`) expand into frames with stable ids (`job_frames`, each a `spec.FrameSpec`); a run
takes its shard's share, skips what the manifest (`manifest`) says is made and checks out, and
has the rest made by workers (`worker`, by the renderer's `sources.FrameSource`) in this process
or a spawned pool (`local`) or on Ray actors (`ray`), each on its chosen EGL device (`egl`); the
parent writes the layout's files (`layouts`: a row per layout, its `store.Store`) through
`shadowvol.io`.  Where a frame is made never changes its bytes.
"""

from __future__ import annotations

from shadowvol.batch.runner import Summary, run

__all__ = ["Summary", "run"]
