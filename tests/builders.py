"""Small scenes and paths shared by the tests (the one builders module; tests never import
from each other).  Vary a built scene with `dataclasses.replace` / `Scene.replace`."""

from __future__ import annotations

import math
import os
from pathlib import Path

from shadowvol.primitives import plane
from shadowvol.scene import Camera, DirectionalLight, Scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"
TEST_OUTPUT = ROOT / "test-output"
# the shared test meshes: ../shared/models beside the checkout, or where SHADOWVOL_MODELS says
# (a worktree elsewhere)
MODELS = Path(os.environ.get("SHADOWVOL_MODELS", ROOT.parent / "shared" / "models"))


def tiny_scene(with_blocker_behind_eye: bool = False) -> Scene:
    camera = Camera(eye=[0, 0, 5], target=[0, 0, 0], fov_y=math.degrees(2 * math.atan(0.2)))
    objects = [plane("backdrop", point=[0, 0, -5], normal=[0, 0, 1], size=[20, 20]),
               plane("A", point=[-1.45, 0, -4], normal=[0, 0, 1], size=[1.1, 4]),
               plane("B", point=[-2.45, 0, -3], normal=[0, 0, 1], size=[1.1, 4])]
    if with_blocker_behind_eye:
        # behind the camera, out of view, between the eye and the light: the eye is in its
        # shadow volume, no visible point is
        objects.append(plane("roof", point=[-3, 0, 8], normal=[0, 0, 1], size=[4, 10]))
    return Scene(camera=camera, objects=objects,
                 lights=[DirectionalLight(direction=[1, 0, -1])], width=4, height=4)
