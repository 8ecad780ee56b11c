"""Which EGL device a batch worker renders on: choose one of the devices, say why.

CUDA_VISIBLE_DEVICES does not select an EGL device (moderngl#732, mujoco#461): EGL lists every
GPU (and Mesa's software device) whatever CUDA sees.  `shadowvol.raster.platform.egl.devices` lists
them with the CUDA device each one is, where EGL_NV_device_cuda says it.
`choose("auto")` takes the EGL device of this process's first visible CUDA device (CUDA device 0,
which CUDA_VISIBLE_DEVICES, Slurm and Ray's `num_gpus` decide), else device 0.

The device queries are `shadowvol.raster.platform.egl.devices` (no context is made, and no GL is
loaded).
"""

from __future__ import annotations

from shadowvol.errors import InputError
from shadowvol.raster.platform.egl import Device, devices


def parse(spec) -> int | str | None:
    """`--egl-device`'s value: None, "auto" or a device index >= 0 (InputError otherwise)."""
    if spec is None or spec == "auto":
        return spec
    if isinstance(spec, int) and not isinstance(spec, bool):
        index = spec
    elif isinstance(spec, str) and spec.strip().isdigit():
        index = int(spec)
    else:
        raise InputError("--egl-device", f"must be 'auto' or a device index (0, 1, ...), "
                                         f"got {spec!r}")
    if index < 0:
        raise InputError("--egl-device", f"must be 'auto' or a device index >= 0, got {index}")
    return index


def choose(spec, found: list[Device] | None = None) -> tuple[int | None, str]:
    """(the device index to pass to `create_context`, a sentence saying which and why).

    spec: None (glcontext's default), "auto", or an index.  An index that is not one of the
    devices found is an InputError naming them."""
    spec = parse(spec)
    if spec is None:
        return None, "EGL device: glcontext's default (device 0 or $GLCONTEXT_DEVICE_INDEX)"
    found = devices() if found is None else found
    listing = ", ".join(d.describe() for d in found) or "none"
    if spec == "auto":
        cuda = [d for d in found if d.cuda_device == 0]
        if cuda:
            return cuda[0].index, (f"EGL device {cuda[0].describe()}: the first visible CUDA "
                                   f"device (EGL_NV_device_cuda); devices: {listing}")
        return 0, (f"EGL device 0: no EGL device is CUDA device 0 (no EGL_NV_device_cuda), so "
                   f"the first; devices: {listing}")
    if found and spec >= len(found):
        raise InputError("--egl-device", f"there is no EGL device {spec}; this machine has "
                                         f"{len(found)}: {listing}")
    chosen = found[spec].describe() if found else str(spec)
    return spec, f"EGL device {chosen}; devices: {listing}"
