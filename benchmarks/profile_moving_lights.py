"""Profile (not a test): the memory of one Renderer over a long run of moving lights.

    python -m benchmarks.profile_moving_lights [--frames 1000] [--samples 16]

`scenes/soft.toml` at 64 x 48 with the camera, a point light and the area light (N samples)
moving every frame, so no light is ever seen twice: the kept shadow volumes of lights gone by
(`CpuVolumes`, bounded by KEPT_OLDER_BYTES and KEPT_OLDER_LIGHTS) are what could grow.  Prints
the process's resident memory and the number of kept light volumes every 100 frames.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 1024


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1000)
    parser.add_argument("--samples", type=int, default=16)
    args = parser.parse_args(argv)

    import shadowvol
    from shadowvol.scene import AreaLight, PointLight

    scene = shadowvol.load_scene(shadowvol.example_scene("soft")).replace(width=64, height=48)
    area = next(light for light in scene.lights if isinstance(light, AreaLight))
    area = dataclasses.replace(area, samples=args.samples)
    point = PointLight([0.5, 4.0, 0.5])
    print("| frame | RSS (MB) | kept light volumes |\n|---:|---:|---:|")
    with shadowvol.Renderer(scene) as r:
        for i in range(args.frames):
            turn = 2 * np.pi * i / 97.0
            eye = scene.camera.eye + 0.3 * np.array([np.cos(turn), 0.0, np.sin(turn)])
            lights = (dataclasses.replace(point, position=point.position + [0.001 * i, 0, 0]),
                      dataclasses.replace(area, center=area.center
                                          + 0.002 * np.array([np.sin(i), 0.0, np.cos(i)])))
            r.render(camera=dataclasses.replace(scene.camera, eye=eye), lights=lights)
            if i % 100 == 0 or i == args.frames - 1:
                kept = sum(len(v._kept) for v in r._volumes.values())
                print(f"| {i} | {rss_mb():.0f} | {kept} |", flush=True)


if __name__ == "__main__":
    main()
