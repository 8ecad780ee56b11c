"""The layouts of `shadowvol batch --format`: one frozen row each, in one table (after
trimesh's exporter table): how a worker makes a frame's bytes, which `Store` writes them, and
where the files go.  A new layout is a row here (and, for a dataset, its module in
`batch.formats`); the runner and the workers read rows, never test a layout's name.

files       OUT/<job>/<frame>.<suffix>, one file per output (`store.FileStore`)
webdataset  OUT/shard-NNNNNN.tar of --samples-per-tar frames (`store.TarStore`)
nerfstudio, bop, coco   OUT/<job>/ in that dataset's layout (`formats.DatasetStore`,
            docs/formats.md)

Frames of the plain layouts (files, webdataset) are the job's outputs and carry no layout in
their spec (so their spec hashes are those of the runs before layouts had names); a dataset
layout's frames carry its name as "format" (`tag`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from shadowvol.batch.formats import DatasetStore, bop, coco, nerfstudio
from shadowvol.batch.formats.arrays import frame_arrays
from shadowvol.batch.outputs import OUTPUTS
from shadowvol.batch.spec import FrameSpec
from shadowvol.batch.store import FileStore, TarStore


@dataclass(frozen=True)
class Layout:
    """One layout.

    store   : the `store.Store` class, made as `store(out, layout)`
    arrays  : (worker, spec, scene, camera, lights) -> the frame's arrays, rendered
    encode  : (spec, arrays, frame scene) -> (name or path -> bytes, the index record or None)
    shards  : its units are tars of `samples_per_tar` frames (else one frame each)
    tag     : the "format" its frame specs carry, None for the plain layouts
    index   : (job, [(spec, record)]) -> {path: bytes}, a dataset's index files, or None
    folders, index_files, first : under OUT/<job>/, the folders of a frame's files, the index
              files, and the folders of what frame 0 adds (where temporaries are cleaned)
    """

    name: str
    store: type
    arrays: Callable
    encode: Callable
    shards: bool = False
    tag: str | None = None
    index: Callable | None = None
    folders: tuple[str, ...] = ()
    index_files: tuple[str, ...] = ()
    first: tuple[str, ...] = ()

    def frames_per_unit(self, samples_per_tar: int) -> int:
        return samples_per_tar if self.shards else 1

    def make_store(self, out):
        return self.store(out, self)


def _outputs_arrays(worker, spec, scene, camera, lights) -> dict:
    return worker.arrays(spec, scene, camera, lights)


def _outputs_encode(spec, arrays, scene) -> tuple[dict[str, bytes], None]:
    """The job's outputs, each encoded by its row of `outputs.OUTPUTS`."""
    return {name: OUTPUTS[name].encode(arrays) for name in spec.outputs}, None


def _dataset(name: str, module, casters: bool, alone: bool, first: tuple = ()) -> Layout:
    return Layout(name, DatasetStore, partial(frame_arrays, casters=casters, alone=alone),
                  module.frame, tag=name, index=module.index, folders=module.FOLDERS,
                  index_files=module.INDEX, first=first)


FILES = Layout("files", FileStore, _outputs_arrays, _outputs_encode)
WEBDATASET = Layout("webdataset", TarStore, _outputs_arrays, _outputs_encode, shards=True)

LAYOUTS: dict[str, Layout] = {layout.name: layout for layout in (
    FILES,
    WEBDATASET,
    _dataset("nerfstudio", nerfstudio, casters=False, alone=False),
    _dataset("bop", bop, casters=False, alone=True, first=bop.FIRST),
    _dataset("coco", coco, casters=True, alone=False),
)}
FORMATS = tuple(LAYOUTS)           # the names --format takes
DATASETS = tuple(name for name, layout in LAYOUTS.items() if layout.tag)

# a frame spec's "format" -> the layout that makes its bytes (the plain layouts make the same)
_BY_TAG = {None: FILES, **{layout.tag: layout for layout in LAYOUTS.values() if layout.tag}}


def of_spec(spec: FrameSpec) -> Layout:
    """The layout that makes the bytes of the frame `spec`."""
    return _BY_TAG[spec.format]


def tag(specs: list[FrameSpec], layout: Layout) -> list[FrameSpec]:
    """A layout's frame specs (so their spec hash, and the worker, know the layout)."""
    return [dataclasses.replace(spec, format=layout.tag) for spec in specs]
