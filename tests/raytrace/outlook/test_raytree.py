"""The ray-tree exercise against trees worked out by hand (a mirror, a glass prism with total
internal reflection, shadow-ray verdicts), and against the renderer: the tree's colour is the
pixel's colour in raytrace.render."""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import SCENES
from PIL import Image

import raytrace
from raytrace.outlook.raytree import (
    BLOCKED,
    FACES_AWAY,
    LIT,
    OUTSIDE_CONE,
    PRIMARY,
    REFLECTED,
    REFRACTED,
    SHADOW,
    TIR,
    format_tree,
    ray_tree,
    tree_colour,
)
from raytrace.tolerances import surface_offset
from shadowvol.cli import raytrace as cli
from shadowvol.course import raytree_slide
from shadowvol.course.slides import Layout
from shadowvol.primitives import mesh, plane
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SpotLight,
)
from shadowvol.scenefile import load_scene, save_scene

N = 9  # odd: the centre pixel's ray runs straight down the view axis, -z
C = N // 2
CAMERA = Camera(eye=[0.0, 0.0, 4.0], target=[0.0, 0.0, 0.0], fov_y=40.0)
MIRROR = Material(ambient=[0.1, 0.1, 0.1], diffuse=[0.3, 0.3, 0.3], specular=[0, 0, 0],
                  reflectivity=0.5)
MATTE = Material(ambient=[0.2, 0.2, 0.2], diffuse=[0.5, 0.5, 0.5], specular=[0, 0, 0])
GLASS = Material(ambient=[0.0, 0.0, 0.0], diffuse=[0.1, 0.1, 0.1], specular=[0, 0, 0],
                 reflectivity=0.1, transparency=0.8, ior=1.5)


def scene_of(objects, lights, **kw):
    return Scene(camera=CAMERA, objects=objects, lights=lights, width=N, height=N,
                 ambient=[0.5, 0.5, 0.5], background=[0.2, 0.3, 0.4], **kw)


def kinds(node):
    return [c.kind for c in node.children]


def mirror_scene():
    """A mirror quad in z = 0 facing the camera, a small matte blocker off the view axis, and
    four lights whose verdicts at the mirror's centre are known:
      0 point at (2, 0, 2): lit;   1 point at (-2, 0, 2): blocked (the blocker sits at
      (-1, 0, 1), on the way);   2 point behind the mirror: it faces away;
      3 spot at (0, 2, 2) aimed away from the mirror (+y): outside its cone."""
    blocker = plane("blocker", point=[-1.0, 0.0, 1.0], normal=[-1.0, 0.0, 1.0],
                    size=[0.4, 0.4], material=MATTE)
    return scene_of([plane("mirror", point=[0, 0, 0], normal=[0, 0, 1], size=[3.0, 3.0],
                           material=MIRROR), blocker],
                    [PointLight([2.0, 0.0, 2.0]), PointLight([-2.0, 0.0, 2.0]),
                     PointLight([0.0, 0.0, -2.0]),
                     SpotLight([0.0, 2.0, 2.0], [0.0, 1.0, 0.0], cone_angle=30.0)])


def test_mirror_tree_by_hand():
    scene = mirror_scene()
    root = ray_tree(scene, C, C, max_depth=2)
    assert root.kind == PRIMARY and root.depth == 0 and root.weight == 1.0
    assert root.obj_name == "mirror" and root.entering
    np.testing.assert_allclose(root.point, [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(root.direction, [0, 0, -1], atol=1e-12)
    assert root.t == pytest.approx(4.0 - CAMERA.near)  # starts on the near plane
    assert kinds(root) == [SHADOW] * 4 + [REFLECTED]
    assert [c.verdict for c in root.children[:4]] == [LIT, BLOCKED, FACES_AWAY, OUTSIDE_CONE]
    assert [c.light for c in root.children[:4]] == [0, 1, 2, 3]
    blocked = root.children[1]
    assert blocked.obj_name == "blocker"
    np.testing.assert_allclose(blocked.point, [-1.0, 0.0, 1.0], atol=1e-3)
    # the shadow rays leave where whitted's leave: offset along the normal facing the viewer
    off = surface_offset(scene)
    np.testing.assert_allclose(root.children[0].origin, root.point + off * root.normal)
    # the mirror ray goes straight back (+z) and hits nothing: the background, weighted 0.5
    refl = root.children[4]
    assert refl.depth == 1 and refl.weight == 0.5 and not refl.hit and refl.children == []
    np.testing.assert_allclose(refl.direction, [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(refl.contribution, 0.5 * scene.background)
    # the mirror's own share: (1 - 0.5) of its Phong term, lit by light 0 alone
    n_dot_l = 2 / math.sqrt(8)
    local = 0.1 * 0.5 + 0.3 * n_dot_l
    np.testing.assert_allclose(root.local, [local] * 3, rtol=1e-12)
    np.testing.assert_allclose(root.contribution, [0.5 * local] * 3, rtol=1e-12)


def test_depth_limit():
    root = ray_tree(mirror_scene(), C, C, max_depth=0)
    assert kinds(root) == [SHADOW] * 4  # no reflected child at the limit
    # ... and the hit's local term counts unweighted
    np.testing.assert_allclose(root.contribution, root.local)


def prism():
    """A glass prism along y: in the xz plane the right triangle (-1, 0), (1, 0), (1, -2), so a
    ray down -z on x = 0 enters the face z = 0 head on, meets the hypotenuse at (0, -1) at 45°
    — more than the critical angle asin(1/1.5) = 41.8° — is totally reflected to +x, and leaves
    through the face x = 1 head on.  y runs over [-1, 2], so no ray here meets a triangle
    diagonal exactly.  Wound outward: refraction tells entering from leaving by the winding."""
    v = []
    for y in (-1.0, 2.0):
        v += [[-1.0, y, 0.0], [1.0, y, 0.0], [1.0, y, -2.0]]
    v = np.array(v)
    faces = np.array([[0, 1, 2], [3, 5, 4],                      # ends
                      [0, 4, 1], [0, 3, 4], [1, 5, 2], [1, 4, 5], [2, 3, 0], [2, 5, 3]])
    tri = v[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    inward = np.einsum("ij,ij->i", normal, v.mean(axis=0) - tri[:, 0]) > 0
    faces[inward] = faces[inward][:, ::-1]
    return mesh("prism", v, faces, GLASS)


def test_total_internal_reflection_by_hand():
    scene = scene_of([prism()], [DirectionalLight([0.0, -1.0, -1.0])])
    root = ray_tree(scene, C, C, max_depth=3)
    # depth 0: the front face, entering; shadow ray, outer reflection, refraction
    assert root.obj_name == "prism" and root.entering
    assert kinds(root) == [SHADOW, REFLECTED, REFRACTED]
    assert root.children[0].verdict == LIT  # light from above-front: the front face is lit
    outer, inside = root.children[1], root.children[2]
    assert not outer.hit and outer.weight == pytest.approx(0.1)
    np.testing.assert_allclose(inside.direction, [0, 0, -1], atol=1e-12)  # head on: no bend
    # depth 1: at the hypotenuse, leaving the glass; Snell has no solution: TIR
    assert inside.depth == 1 and inside.hit and not inside.entering
    np.testing.assert_allclose(inside.point, [0, 0, -1], atol=1e-6)
    assert kinds(inside) == [SHADOW, REFLECTED, TIR]
    assert inside.children[0].verdict == BLOCKED  # from inside, the prism is in the way
    internal, tir = inside.children[1], inside.children[2]
    np.testing.assert_allclose(tir.direction, [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(internal.direction, tir.direction)  # both the mirror direction
    assert tir.weight == pytest.approx(0.8 * 0.8) and internal.weight == pytest.approx(0.8 * 0.1)
    # depth 2: the face x = 1, head on, leaving: it refracts out (no TIR) and, at depth 3, ends
    assert tir.hit and not tir.entering
    # (it started off the hypotenuse by the surface offset along the normal (1, 0, 1)/sqrt 2)
    off = surface_offset(scene) / math.sqrt(2)
    np.testing.assert_allclose(tir.origin, [off, 0, -1 + off], atol=1e-9)
    np.testing.assert_allclose(tir.point, [1, 0, -1 + off], atol=1e-9)
    assert kinds(tir) == [SHADOW, REFLECTED, REFRACTED]
    out = tir.children[2]
    assert out.depth == 3 and not out.hit and out.children == []
    np.testing.assert_allclose(out.direction, [1, 0, 0], atol=1e-12)
    assert tir.children[1].depth == 3 and tir.children[1].hit  # back inside, to the hypotenuse
    assert [c.kind for c in tir.children[1].children] == [SHADOW]  # depth limit


def test_the_text_lists_every_ray():
    scene = scene_of([prism()], [DirectionalLight([0.0, -1.0, -1.0])])
    root = ray_tree(scene, C, C, max_depth=2)
    text = format_tree(root, scene)
    lines = text.splitlines()
    n = len(list(root.walk()))
    assert len(lines) == n + 1
    assert [l.lstrip("|` -").split()[0] for l in lines[:n]] == [f"#{k}" for k in range(n)]
    assert "tir" in text and "blocked by 'prism'" in text
    # children are indented one level more than their parent
    assert lines[1].startswith("|- #1 shadow") and lines[-2].startswith("   ")


@pytest.mark.parametrize("make", [mirror_scene,
                                  lambda: scene_of([prism()],
                                                   [DirectionalLight([0.0, -1.0, -1.0])])],
                         ids=["mirror", "prism"])
def test_tree_colour_is_the_rendered_pixel_small_scenes(make):
    scene = make()
    image = raytrace.render(scene, max_depth=3)
    for y in range(N):
        for x in range(N):
            got = tree_colour(ray_tree(scene, x, y, max_depth=3))
            np.testing.assert_allclose(got, image[y, x], rtol=1e-9, atol=1e-12)


def test_tree_colour_is_the_rendered_pixel_whitted():
    """Every pixel of a reduced whitted.toml: mirror ball, glass ball, box, floor, shadows."""
    scene = load_scene(SCENES / "whitted.toml").replace(width=40, height=30)
    image = raytrace.render(scene)
    deep = 0
    for y in range(scene.height):
        for x in range(scene.width):
            tree = ray_tree(scene, x, y)
            deep = max(deep, max(n.depth for n in tree.walk()))
            np.testing.assert_allclose(tree_colour(tree), image[y, x], rtol=1e-9, atol=1e-12,
                                       err_msg=f"pixel ({x}, {y})")
    assert deep == scene.max_depth  # the glass ball sends rays down to the depth limit


def test_bad_pixel_and_depth():
    scene = mirror_scene()
    with pytest.raises(ValueError, match="outside"):
        ray_tree(scene, N, 0)
    with pytest.raises(ValueError, match="max_depth"):
        ray_tree(scene, 0, 0, max_depth=-1)


def test_picture_and_cli(tmp_path, capsys):
    """`raytrace tree -o` draws the gallery's slide: the same pixels as
    `raytree_slide.slide` at 1920x1080, one sample a pixel."""
    scene = load_scene(SCENES / "whitted.toml").replace(width=64, height=48)
    small = tmp_path / "whitted.json"
    save_scene(scene, small)
    out = tmp_path / "tree.png"
    code = cli.main(["tree", str(small), "--pixel", "42", "30", "--depth", "2", "-o", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert text.startswith("#0 primary") and "hits 'glass ball'" in text
    assert text.splitlines()[-1].startswith("pixel colour")
    drawn = np.asarray(Image.open(out).convert("RGB"))
    scene = load_scene(small)  # as the command reads it
    tree = ray_tree(scene, 42, 30, max_depth=2)
    slide = raytree_slide.slide(Layout(supersample=1), scene, tree, (42, 30), 2,
                                lambda s: raytrace.render(s, max_depth=2, progress=False))
    assert drawn.shape == (1080, 1920, 3)
    np.testing.assert_array_equal(drawn, slide)
    assert cli.main(["tree", str(small), "--pixel", "64", "0"]) == 2
    assert cli.main(["tree", str(small), "--pixel", "0", "0", "--depth", "-1"]) == 2
