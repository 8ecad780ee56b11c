"""The layouts of `shadowvol batch --format`: one frozen row each, in one table (after
trimesh's exporter table): how a worker makes a frame's bytes, which `Store` writes them, and
where the files go.  A new layout is a row here (and, for a dataset, its module in
`batch.datasets`); the runner and the workers read rows, never test a layout's name.

files       OUT/<job>/<frame>.<suffix>, one file per output (`store.FileStore`)
webdataset  OUT/shard-NNNNNN.tar of --samples-per-tar frames (`store.TarStore`)
nerfstudio, coco, istd, soba, soba-lights   OUT/<job>/ in that dataset's layout (COCO's merged
            index OUT/annotations.json too), bop OUT/train/<job's place>/ and OUT/models/
            (`datasets.DatasetStore`, docs/formats.md)

Frames of the plain layouts (files, webdataset) are the job's outputs and carry no layout in
their spec (so their spec hashes are those of the runs before layouts had names); a dataset
layout's frames carry its name (`tag`: `FrameSpec.layout`, stored under the key "format", the
name of the flag that picks it, so that the spec hashes of earlier runs still hold).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from shadowvol.batch.datasets import DatasetStore, bop, coco, istd, nerfstudio, soba
from shadowvol.batch.datasets.arrays import frame_arrays
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
    tag     : the `layout` its frame specs carry, None for the plain layouts
    index   : (job, [(spec, record)]) -> {path: bytes}, a dataset's index files, or None
    dataset_index : (specs, records by id, scene_of) -> {path: bytes}, the index files of a
              dataset of every job (ids shared by its jobs: COCO's categories and image ids,
              BOP's models and scene folders), in place of `index`; its frame specs carry
              their job's place (`tag`), and its store the run's scenes (`scene_of(key)`)
    root    : spec -> the folder of the frame's files under OUT (None: `<job>`)
    folders, index_files, first : under the frame's folder, the folders of a frame's files
              and the index files; `first`: what frame 0 adds there (folders), or for a
              `dataset_index`, what it writes under OUT (folders, or files: `name.json`)
              (where temporaries are cleaned)
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
    dataset_index: Callable | None = None
    root: Callable | None = None

    def frames_per_unit(self, samples_per_tar: int) -> int:
        return samples_per_tar if self.shards else 1

    def make_store(self, out, scenes: dict | None = None):
        """Its store of `out`; a `dataset_index` layout's is given the run's `scenes` (key ->
        path or Scene)."""
        if self.dataset_index is not None:
            return self.store(out, self, scenes)
        return self.store(out, self)


def _outputs_arrays(worker, spec, scene, camera, lights) -> dict:
    return worker.arrays(spec, scene, camera, lights)


def _outputs_encode(spec, arrays, scene) -> tuple[dict[str, bytes], None]:
    """The job's outputs, each encoded by its row of `outputs.OUTPUTS`."""
    return {name: OUTPUTS[name].encode(arrays) for name in spec.outputs}, None


def _dataset(name: str, module, casters: bool, alone: bool, first: tuple = ()) -> Layout:
    return Layout(name, DatasetStore, partial(frame_arrays, casters=casters, alone=alone),
                  module.frame, tag=name, index=getattr(module, "index", None),
                  folders=module.FOLDERS, index_files=module.INDEX, first=first,
                  dataset_index=getattr(module, "dataset_index", None),
                  root=getattr(module, "root", None))


def _own(name: str, module, arrays: Callable, encode: Callable) -> Layout:
    """A dataset layout that renders its own arrays (the shadow-free twin, the casters)."""
    return Layout(name, DatasetStore, arrays, encode, tag=name, index=module.index,
                  folders=module.FOLDERS, index_files=module.INDEX)


FILES = Layout("files", FileStore, _outputs_arrays, _outputs_encode)
WEBDATASET = Layout("webdataset", TarStore, _outputs_arrays, _outputs_encode, shards=True)

LAYOUTS: dict[str, Layout] = {layout.name: layout for layout in (
    FILES,
    WEBDATASET,
    _dataset("nerfstudio", nerfstudio, casters=False, alone=False),
    _dataset("bop", bop, casters=False, alone=True, first=bop.FIRST),
    _dataset("coco", coco, casters=True, alone=False, first=coco.FIRST),
    _own("istd", istd, istd.arrays, istd.frame),
    _own("soba", soba, soba.arrays, partial(soba.frame, per_light=False)),
    _own("soba-lights", soba, soba.arrays, partial(soba.frame, per_light=True)),
)}
DATASETS = tuple(name for name, layout in LAYOUTS.items() if layout.tag)

# a frame spec's `layout` -> the layout that makes its bytes (the plain layouts make the same)
_BY_TAG = {None: FILES, **{layout.tag: layout for layout in LAYOUTS.values() if layout.tag}}


def of_spec(spec: FrameSpec) -> Layout:
    """The layout that makes the bytes of the frame `spec`."""
    return _BY_TAG[spec.layout]


def tag(specs: list[FrameSpec], layout: Layout, job_index: int | None = None
        ) -> list[FrameSpec]:
    """A layout's frame specs (so their spec hash, and the worker, know the layout), with
    their job's place in the job file where the layout's index is of the whole dataset."""
    place = {"job_index": job_index} if layout.dataset_index is not None else {}
    return [dataclasses.replace(spec, layout=layout.tag, **place) for spec in specs]
