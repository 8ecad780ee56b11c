"""Textures, MTL colours and vertex colours in the ray tracers (docs/CONVENTIONS.md,
"Textures"), from files written here: Whitted's pixels are the texel the rule picks under the
pixel centre's UV, computed independently in float64 (scalar Python, the camera and the quad's
plane from the conventions); the path tracer's direct light is Whitted's; an OBJ whose MTL says
`Kd 1 0 0` renders red; PLY vertex colours render; what is not read is one warning naming the
file; a missing or unreadable texture is one error line and exit status 2."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from builders import (
    GL_CLAMP,
    GL_LINEAR,
    GL_MIRROR,
    GL_NEAREST,
    GL_REPEAT,
    QUAD,
    QUAD_UV,
    textured_glb,
    textured_scene_file,
)

import raytrace
from raytrace.outlook.path import pathtrace
from shadowvol import memory
from shadowvol.cli.raytrace import main
from shadowvol.errors import IgnoredMaterial
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

# Whitted shades in float64 from the float64 hit: it must give the float64 answer to rounding
FLOAT64_TOL = 1e-9
# the path tracer's state is float32 (`raytrace.outlook.path.pathstate.STATE`): a direct-light value of at
# most 1 carries a few float32 roundings, ~1e-7 each
FLOAT32_TOL = 1e-5
SAMPLERS = [(GL_NEAREST, GL_REPEAT), (GL_LINEAR, GL_REPEAT), (GL_NEAREST, GL_CLAMP),
            (GL_LINEAR, GL_CLAMP), (GL_LINEAR, GL_MIRROR)]
FACTOR = (0.9, 0.7, 0.8, 1.0)
# the quad's COLOR_0, linear (glTF), one colour a corner
COLOURS = np.array([[1.0, 0.5, 0.5], [0.5, 1.0, 0.5], [0.5, 0.5, 1.0], [1.0, 1.0, 0.25]],
                   np.float32)


def texels(seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (8, 8, 3)).astype(np.uint8)


def decode(code: int) -> float:
    c = code / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def wrapped(i: int, n: int, wrap: int) -> int:
    if wrap == GL_REPEAT:
        return i % n
    if wrap == GL_CLAMP:
        return min(max(i, 0), n - 1)
    k = i % (2 * n)
    return k if k < n else 2 * n - 1 - k


def texel_at(tex: np.ndarray, u: float, v: float, filt: int, wrap: int) -> np.ndarray:
    """The rule, scalar: the texel (or the bilinear mix of four) under (u, v)."""
    h, w = tex.shape[:2]

    def at(i, j):
        return np.array([decode(int(c)) for c in tex[wrapped(j, h, wrap), wrapped(i, w, wrap)]])

    if filt == GL_NEAREST:
        return at(math.floor(u * w), math.floor(v * h))
    x, y = u * w - 0.5, v * h - 0.5
    i, j = math.floor(x), math.floor(y)
    a, b = x - i, y - j
    return ((at(i, j) * (1 - a) + at(i + 1, j) * a) * (1 - b)
            + (at(i, j + 1) * (1 - a) + at(i + 1, j + 1) * a) * b)


def ground_point(scene, x: int, y: int) -> np.ndarray:
    """(3,) float64: where pixel (x, y)'s centre ray meets the ground (y = 0), from the
    conventions alone."""
    cam = scene.camera
    eye = cam.eye
    forward = (cam.target - eye) / np.linalg.norm(cam.target - eye)
    right = np.cross(forward, cam.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    half = math.tan(math.radians(cam.fov_y) / 2)
    nx = (x + 0.5) / scene.width * 2 - 1
    ny = 1 - (y + 0.5) / scene.height * 2
    d = forward + nx * half * scene.aspect * right + ny * half * up
    return eye - eye[1] / d[1] * d


def expected_pixel(scene, x: int, y: int, tex, filt, wrap) -> tuple[np.ndarray, float, float]:
    """The float64 colour of pixel (x, y) of the quad scene, from the conventions alone, and
    the continuous texel coordinates under it (u w, v h)."""
    eye = scene.camera.eye
    p = ground_point(scene, x, y)
    s, t = (p[0] + 1) / 2, (p[2] + 1) / 2               # the quad's own (0..1) coordinates
    uv0, uv2 = scene.objects[0].uv[0], scene.objects[0].uv[2]   # as loaded (float32 file)
    u, v = uv0[0] + s * (uv2[0] - uv0[0]), uv0[1] + t * (uv2[1] - uv0[1])
    base = texel_at(tex, u, v, filt, wrap)
    colours = scene.objects[0].colors
    if colours is not None:   # barycentric in triangle (0, 1, 2) (t <= s) or (0, 2, 3)
        w = [1 - s, s - t, t, 0.0] if t <= s else [1 - t, 0.0, s, t - s]
        base = base * (np.array(w) @ colours)
    m = scene.objects[0].material
    light = scene.lights[0]
    n = np.array([0.0, 1.0, 0.0])
    l = (light.position - p) / np.linalg.norm(light.position - p)
    view = (eye - p) / np.linalg.norm(eye - p)
    r = 2 * n.dot(l) * n - l
    colour = m.ambient * base * scene.ambient + (m.diffuse * base * max(n.dot(l), 0.0)
                                                 + m.specular * max(r.dot(view), 0.0)
                                                 ** m.shininess) * light.radiance
    h, w = tex.shape[:2]
    return colour, u * w, v * h


def quad_scene(tmp_path, filt, wrap, seed=0, colours=None):
    tex = texels(seed)
    textured_glb(tmp_path / "quad.glb", tex, wrap=wrap, filt=filt, factor=FACTOR,
                 colours=colours)
    return load_scene(textured_scene_file(tmp_path, "quad.glb")), tex


def on_quad(scene) -> np.ndarray:
    """(k, 2) pixels (x, y) whose centre sees the quad well inside its edges."""
    ids = raytrace.ground_truth(scene, outputs=("object_id",)).object_id
    inner = ids[1:-1, 1:-1] & ids[:-2, 1:-1] & ids[2:, 1:-1] & ids[1:-1, :-2] & ids[1:-1, 2:]
    y, x = np.nonzero(inner)
    return np.stack([x + 1, y + 1], 1)


@pytest.mark.parametrize("colours", [None, COLOURS], ids=["texture", "texture+COLOR_0"])
@pytest.mark.parametrize("filt,wrap", SAMPLERS)
def test_whitted_pixels_are_the_rules_texels(tmp_path, filt, wrap, colours):
    scene, tex = quad_scene(tmp_path, filt, wrap, colours=colours)
    if colours is not None:   # glTF's COLOR_0 is linear: read as it is, not decoded
        np.testing.assert_array_equal(scene.objects[0].colors, colours.astype(np.float64))
    image = raytrace.render(scene, max_depth=0, progress=False)
    pixels = on_quad(scene)
    assert len(pixels) > 2000
    picked = pixels[np.random.default_rng(1).choice(len(pixels), 200, replace=False)]
    checked = 0
    for x, y in picked:
        want, tx, ty = expected_pixel(scene, x, y, tex, filt, wrap)
        if filt == GL_NEAREST and min(abs(tx - round(tx)), abs(ty - round(ty))) < 1e-6:
            continue   # a texel edge under the pixel centre: which texel is rounding
        np.testing.assert_allclose(image[y, x], want, rtol=0, atol=FLOAT64_TOL,
                                   err_msg=f"pixel ({x}, {y})")
        checked += 1
    assert checked > 190
    # the texture shows: every texel of the 8x8 in view gives its own colour
    assert len(np.unique(image[pixels[:, 1], pixels[:, 0]].round(6), axis=0)) > 40


def test_wrap_and_filter_change_the_image(tmp_path):
    images = {}
    for filt, wrap in SAMPLERS:
        folder = tmp_path / f"{filt}-{wrap}"
        folder.mkdir()
        images[filt, wrap] = raytrace.render(quad_scene(folder, filt, wrap)[0], max_depth=0,
                                             progress=False)
    for a in SAMPLERS:
        for b in SAMPLERS:
            if a < b:
                assert (np.abs(images[a] - images[b]) > 1e-3).any(), (a, b)


def test_the_path_tracers_direct_light_is_whitteds(tmp_path):
    """At max_depth 1 with no emitters and no specular term, a pixel-centre path is kd times
    the texture times n . l times the radiance, as Whitted's diffuse term."""
    scene, _ = quad_scene(tmp_path, GL_LINEAR, GL_REPEAT)
    quad = scene.objects[0]
    matte = dataclasses.replace(quad, material=dataclasses.replace(
        quad.material, specular=np.zeros(3)))
    scene = scene.replace(objects=(matte,), ambient=np.zeros(3), width=48, height=40)
    whitted = raytrace.render(scene, max_depth=0, progress=False)
    path = pathtrace.render(scene, spp=1, max_depth=1, jitter=False, progress=False)
    assert path.shading == "numpy"      # the compiled shading reads no texture
    np.testing.assert_allclose(path.image, whitted, rtol=0, atol=FLOAT32_TOL)
    assert len(np.unique(whitted.reshape(-1, 3).round(5), axis=0)) > 100


def write_obj(folder, kd="1 0 0", extra=""):
    (folder / "m.mtl").write_text(f"newmtl red\nKd {kd}\n{extra}")
    (folder / "m.obj").write_text("mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
                                  "usemtl red\nf 1 2 3\nf 1 3 4\n")


def test_an_obj_whose_mtl_says_kd_1_0_0_renders_red(tmp_path):
    write_obj(tmp_path)
    scene = load_scene(textured_scene_file(tmp_path, "m.obj"))
    np.testing.assert_array_equal(scene.objects[0].material.diffuse, [1, 0, 0])
    image = raytrace.render(scene, max_depth=0, progress=False)
    seen = image[on_quad(scene)[:, 1], on_quad(scene)[:, 0]]
    # red, but for the white specular highlight (ks 0.2 grey) where it is
    assert (seen[:, 0] > 0.1).all() and (seen[:, 1] == seen[:, 2]).all()
    assert seen[:, 1].mean() < 0.02 * seen[:, 0].mean() and (seen[:, 0] > 4 * seen[:, 1]).all()


def test_ply_vertex_colours_render(tmp_path):
    rows = ["-1 0 -1 255 0 0", "1 0 -1 0 255 0", "1 0 1 0 0 255", "-1 0 1 255 255 255"]
    (tmp_path / "c.ply").write_text(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        + "\n".join(rows) + "\n3 0 1 2\n3 0 2 3\n")
    scene = load_scene(textured_scene_file(tmp_path, "c.ply"))
    np.testing.assert_array_equal(scene.objects[0].colors[:3], np.eye(3))
    image = raytrace.render(scene, max_depth=0, progress=False)
    pixels = on_quad(scene)
    points = np.array([ground_point(scene, x, y) for x, y in pixels])
    # at the pixel seeing the point nearest each corner the corner's colour dominates: red,
    # green, blue at corners 0, 1, 2 (white at 3), where they are in view
    shown = 0
    for corner, channel in ((0, 0), (1, 1), (2, 2)):
        gap = np.linalg.norm(points - QUAD[corner], axis=1)
        if gap.min() < 0.3:
            x, y = pixels[gap.argmin()]
            assert image[y, x].argmax() == channel, (corner, image[y, x])
            shown += 1
    assert shown >= 2


def test_what_is_not_read_is_one_warning_naming_the_file(tmp_path, capsys):
    textured_glb(tmp_path / "quad.glb", texels(), material={
        "normalTexture": {"index": 0}, "alphaMode": "MASK", "occlusionTexture": {"index": 0}})
    path = textured_scene_file(tmp_path, "quad.glb")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_scene(path)
    assert len(caught) == 1 and caught[0].category is IgnoredMaterial
    text = str(caught[0].message)
    for name in ("quad.glb", "normalTexture", "occlusionTexture", "alphaMode MASK", "opaque"):
        assert name in text
    assert main(["render", str(path), "-o", str(tmp_path / "a.png"), "--no-progress"]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "quad.glb" in line]
    assert len(err) == 1 and err[0].startswith("warning: "), err


def test_an_untextured_file_warns_nothing(tmp_path):
    write_obj(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_scene(textured_scene_file(tmp_path, "m.obj"))


@pytest.mark.parametrize("case", ["missing png", "garbage png", "missing map_Kd", "bad mtl"])
def test_a_bad_texture_is_one_line_and_exit_2(tmp_path, capsys, case):
    if case == "missing png":
        textured_glb(tmp_path / "quad.glb", None, image_uri="gone.png")
        mesh, name = "quad.glb", "gone.png"
    elif case == "garbage png":
        textured_glb(tmp_path / "quad.glb", texels(), image_uri="bad.png")
        (tmp_path / "bad.png").write_bytes(b"not a png")
        mesh, name = "quad.glb", "bad.png"
    elif case == "missing map_Kd":
        write_obj(tmp_path, extra="map_Kd nothere.png\n")
        mesh, name = "m.obj", "nothere.png"
    else:
        write_obj(tmp_path, kd="1 zero 0")
        mesh, name = "m.obj", "m.mtl"
    path = textured_scene_file(tmp_path, mesh)
    assert main(["render", str(path), "-o", str(tmp_path / "a.png"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("error: ") and name in err
    assert "Traceback" not in err
    assert not (tmp_path / "a.png").exists()


def test_the_quad_is_where_the_tests_think(tmp_path):
    """The builders' quad: the UV map the float64 check assumes is affine in x and z."""
    scene, _ = quad_scene(tmp_path, GL_NEAREST, GL_REPEAT)
    quad = scene.objects[0]
    np.testing.assert_array_equal(quad.vertices, QUAD.astype(np.float64))
    np.testing.assert_allclose(quad.uv, QUAD_UV.astype(np.float64), rtol=0, atol=1e-7)


def test_textures_count_in_the_memory_budget(tmp_path):
    """A 1024 x 512 texture adds its texels to every renderer's estimate (the model's codes,
    the ray tracer's float64 copy, the GL buffer and its upload), the G-buffer's UVs and
    colours to the raster's; a budget that fits the untextured scene refuses it."""
    import raytrace.outlook.estimate
    import shadowvol.raster.estimate

    big = np.random.default_rng(0).integers(0, 256, (512, 1024, 3)).astype(np.uint8)
    textured_glb(tmp_path / "quad.glb", big)
    scene = load_scene(textured_scene_file(tmp_path, "quad.glb"))
    quad = scene.objects[0]
    plain = scene.replace(objects=(dataclasses.replace(
        quad, uv=None, material=dataclasses.replace(quad.material, texture=None)),))
    n = 512 * 1024
    assert raytrace.outlook.estimate.whitted(scene).total - raytrace.outlook.estimate.whitted(plain).total == n * 27
    assert raytrace.outlook.estimate.path_traced(scene, 4).total - raytrace.outlook.estimate.path_traced(plain, 4).total == n * 27
    px = scene.width * scene.height
    assert shadowvol.raster.estimate.render(scene).total - shadowvol.raster.estimate.render(plain).total == n * 11 + 24 * px
    assert shadowvol.raster.estimate.render(scene, gl_in_host=False).total - \
        shadowvol.raster.estimate.render(plain, gl_in_host=False).total == n * 7
    limit = memory.BASE + raytrace.outlook.estimate.whitted(plain).total + n * 10
    memory.check(raytrace.outlook.estimate.whitted(plain), limit)
    with pytest.raises(SceneError, match="budget"):
        memory.check(raytrace.outlook.estimate.whitted(scene), limit)
    assert "textures" in raytrace.outlook.estimate.whitted(scene).describe()


@pytest.mark.parametrize("suffix", [".toml", ".json"])
@pytest.mark.parametrize("where", ["in the GLB", "beside it"])
def test_textured_meshes_survive_save_scene(tmp_path, suffix, where):
    """save_scene writes the UVs, the vertex colours and the texture as the file it was read
    from (the GLB and its image index, or the image file): loaded again, the same scene."""
    textured_glb(tmp_path / "quad.glb", texels(2), wrap=GL_CLAMP, filt=GL_LINEAR,
                 image_uri=None if where == "in the GLB" else "tex.png")
    scene = load_scene(textured_scene_file(tmp_path, "quad.glb"))
    quad = scene.objects[0]
    colours = np.linspace(0.2, 1.0, 12).reshape(4, 3)
    scene = scene.replace(objects=(dataclasses.replace(quad, colors=colours),))
    saved = tmp_path / "elsewhere" / f"saved{suffix}"
    saved.parent.mkdir()
    from shadowvol.scenefile import save_scene

    save_scene(scene, saved)
    again = load_scene(saved).objects[0]
    t, u = quad.material.texture, again.material.texture
    np.testing.assert_array_equal(u.texels, t.texels)
    assert (u.wrap_s, u.wrap_t, u.filter, u.file, u.image) == \
        (t.wrap_s, t.wrap_t, t.filter, t.file, t.image)
    assert (u.image is None) == (where == "beside it")
    np.testing.assert_array_equal(again.uv, quad.uv)
    np.testing.assert_array_equal(again.colors, colours)
    np.testing.assert_array_equal(
        raytrace.render(load_scene(saved), max_depth=0, progress=False),
        raytrace.render(scene, max_depth=0, progress=False))


@pytest.mark.parametrize("texture,key", [
    ({"file": "tex.png", "wrap_s": "wrap"}, "objects[0].material.texture.wrap_s"),
    ({"file": "tex.png", "filter": "cubic"}, "objects[0].material.texture.filter"),
    ({"file": "none.png"}, "objects[0].material.texture"),
    ({"file": "quad.glb", "image": 3}, "objects[0].material.texture"),
    ({"image": 0}, "objects[0].material.texture.file")])
def test_a_bad_texture_table_names_its_key(tmp_path, texture, key):
    from shadowvol.scenefile import scene_from_dict

    textured_glb(tmp_path / "quad.glb", texels(), image_uri="tex.png")
    data = {"camera": {"eye": [0, 2, 2], "target": [0, 0, 0]},
            "objects": [{"type": "mesh", "vertices": QUAD.tolist(), "faces": [[0, 1, 2]],
                         "uv": QUAD_UV.tolist(), "material": {"texture": texture}}]}
    with pytest.raises(SceneError) as caught:
        scene_from_dict(data, tmp_path)
    assert str(caught.value).startswith(key + ":"), str(caught.value)
