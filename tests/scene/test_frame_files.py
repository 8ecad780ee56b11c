"""The writers of a frame's ground truth (shadowvol.frame, shadowvol.io): the mask file's extra
arrays, checked by name, dtype and shape; linear OpenEXR read back by the OpenEXR package;
16-bit PNG read back by Pillow; and the camera matrices (shadowvol.cameras) against their
definitions."""

from __future__ import annotations

import math
import struct
import zlib

import numpy as np
import OpenEXR
import pytest
from PIL import Image

from shadowvol.cameras import GL_TO_CV, calibration, project, unproject
from shadowvol.frame import save_masks
from shadowvol.io import (
    encode_srgb,
    load_mask_arrays,
    load_masks,
    save_exr,
    save_png16,
)
from shadowvol.primitives import plane
from shadowvol.scene import Camera, DirectionalLight, PointLight, Scene, SpotLight


def small_scene() -> Scene:
    return Scene(camera=Camera(eye=[1.0, 2.0, 4.0], target=[0.0, 0.3, 0.0], fov_y=50.0),
                 objects=[plane("floor")],
                 lights=[PointLight([1, 3, 1]), DirectionalLight([0, -1, 0]),
                         SpotLight([0, 3, 0], [0, -1, 0], 20.0)], width=8, height=6)


def test_mask_file_holds_the_extra_arrays_and_refuses_wrong_ones(tmp_path):
    scene = small_scene()
    lit = np.zeros((3, 6, 8), bool)
    cov = np.ones((6, 8), bool)
    arrays = calibration(scene).arrays() | {
        "depth": np.full((6, 8), 2.5, np.float32), "casters": np.ones((3, 6, 8, 1), np.uint64)}
    save_masks(tmp_path / "m.npz", lit, cov, arrays=arrays)
    back = load_mask_arrays(tmp_path / "m.npz")
    assert set(back) == {"lit", "coverage"} | set(arrays)
    for name, value in arrays.items():
        assert back[name].dtype == value.dtype
        np.testing.assert_array_equal(back[name], value)
    assert [a.shape for a in load_masks(tmp_path / "m.npz")] == [(3, 6, 8), (6, 8)]
    with pytest.raises(ValueError, match=r"depth must be float32\(6, 8\), got float64"):
        save_masks(tmp_path / "bad.npz", lit, cov, arrays={"depth": np.zeros((6, 8))})
    with pytest.raises(ValueError, match=r"facing must be bool\(3, 6, 8\)"):
        save_masks(tmp_path / "bad.npz", lit, cov, arrays={"facing": np.zeros((2, 6, 8), bool)})
    with pytest.raises(ValueError, match="holds no array 'depths'"):
        save_masks(tmp_path / "bad.npz", lit, cov, arrays={"depths": np.zeros((6, 8), np.float32)})
    assert not (tmp_path / "bad.npz").exists()


def test_exr_reads_back_exactly_with_the_openexr_package(tmp_path):
    rng = np.random.default_rng(7)
    image = (rng.random((37, 53, 3)) * 4).astype(np.float32)
    image[:20, :30] = 0.25  # flat runs compress; noise does not (stored as it is)
    image[0, 0] = [1e-30, 65504.0, 1e30]
    save_exr(tmp_path / "a.exr", image)
    with OpenEXR.File(str(tmp_path / "a.exr")) as f:
        rgb = f.channels()["RGB"].pixels
        assert f.header()["compression"] == OpenEXR.ZIP_COMPRESSION
    assert rgb.dtype == np.float32 and rgb.shape == (37, 53, 3)
    np.testing.assert_array_equal(rgb, image)
    assert (tmp_path / "a.exr").stat().st_size < image.nbytes


def test_png16_reads_back_with_pillow(tmp_path):
    ramp = np.linspace(0, 1, 64 * 48 * 3).reshape(48, 64, 3)
    save_png16(tmp_path / "a.png", ramp)
    data = (tmp_path / "a.png").read_bytes()
    width, height, depth, colour = struct.unpack(">IIBB", data[16:26])
    assert (width, height, depth, colour) == (64, 48, 16, 2)
    with Image.open(tmp_path / "a.png") as im:
        assert im.size == (64, 48)
        im.load()
        eight = np.asarray(im.convert("RGB"))
    # Pillow reads 16-bit RGB as 8 bits, the high byte: the 16-bit sRGB values >> 8
    raw = np.frombuffer(zlib.decompress(data[data.index(b"IDAT") + 4:data.index(b"IEND") - 8]),
                        np.uint8).reshape(48, 1 + 64 * 6)
    assert (raw[:, 0] == 0).all()
    sixteen = raw[:, 1:].copy().view(">u2").reshape(48, 64, 3)
    np.testing.assert_array_equal(eight, (sixteen >> 8).astype(np.uint8))
    # and they are the sRGB curve at 16 bits: within one 8-bit step of the 8-bit encoding
    assert np.abs(eight.astype(int) - encode_srgb(ramp)).max() <= 1
    assert len(np.unique(sixteen)) > 4 * len(np.unique(encode_srgb(ramp)))


def test_camera_matrices_follow_their_conventions():
    scene = small_scene()
    cal = calibration(scene)
    cam = scene.camera
    f = (6 / 2) / math.tan(math.radians(50.0) / 2)
    np.testing.assert_allclose(cal.K, [[f, 0, 4], [0, f, 3], [0, 0, 1]])
    # the two conventions differ by the axis flip; each is a rigid motion
    np.testing.assert_allclose(cal.camera_to_world @ GL_TO_CV @ cal.world_to_camera, np.eye(4),
                               atol=1e-12)
    np.testing.assert_allclose(cal.world_to_camera[:3, :3] @ cal.world_to_camera[:3, :3].T,
                               np.eye(3), atol=1e-12)
    # OpenCV: the target is straight ahead (+z), world up points up the image (−y)
    target = cal.world_to_camera @ np.append(cam.target, 1)
    assert target[2] > 0 and np.allclose(target[:2], 0)
    assert (cal.world_to_camera[:3, :3] @ [0, 1, 0])[1] < 0
    # the target projects to the image centre (W/2, H/2)
    np.testing.assert_allclose(project(cal.K, cal.world_to_camera, cam.target[None]), [[4, 3]])
    # OpenGL: camera_to_world's third column points back, from the target to the eye
    back = cal.camera_to_world[:3, 2]
    np.testing.assert_allclose(back, (cam.eye - cam.target) / np.linalg.norm(cam.eye - cam.target))
    np.testing.assert_allclose(cal.camera_to_world[:3, 3], cam.eye)
    # unprojecting depth 2 and projecting back gives the pixel centres; depth is along the axis
    depth = np.full((6, 8), 2.0)
    world = unproject(cal.K, cal.camera_to_world, depth)
    np.testing.assert_allclose(project(cal.K, cal.world_to_camera, world.reshape(-1, 3)),
                               np.stack(np.meshgrid(np.arange(8) + 0.5, np.arange(6) + 0.5),
                                        -1).reshape(-1, 2))
    np.testing.assert_allclose((world - cam.eye) @ -back, 2.0)
    # the lights: homogeneous positions, directions (0 for a point light)
    np.testing.assert_allclose(cal.light_position, [[1, 3, 1, 1], [0, 1, 0, 0], [0, 3, 0, 1]])
    np.testing.assert_allclose(cal.light_direction, [[0, 0, 0], [0, -1, 0], [0, -1, 0]])


def test_area_lights_in_the_light_arrays():
    from shadowvol.scene import AreaLight

    rect = AreaLight("rect", [0.0, 2.5, 0.0], normal=[0.0, -1.0, 0.0], size=[1.0, 1.0],
                     samples=4)
    ball = AreaLight("sphere", [1.0, 2.0, 0.0], radius=0.3, samples=4)
    scene = small_scene().replace(lights=(rect, ball))
    cal = calibration(scene)
    np.testing.assert_allclose(cal.light_position, [[0, 2.5, 0, 1], [1, 2, 0, 1]])
    np.testing.assert_allclose(cal.light_direction, [[0, -1, 0], [0, 0, 0]])
