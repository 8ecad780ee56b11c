"""Memory: an image over the memory budget is refused before anything big is allocated (one
line naming the file and `image`, status 2), and running out of memory anywhere in any command
of either tool is one line, `error: out of memory while ...`, status 3, no traceback and no
file written.  The model itself is checked against measured peaks in test_memory_model.py."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
import types

import numpy as np
import pytest
from builders import ROOT, SCENES

import raytrace.estimate
import raytrace.exercise
import raytrace.masks
import raytrace.outlook.estimate
import raytrace.outlook.path.pathtrace
import raytrace.outlook.radiosity
import raytrace.outlook.whitted
import shadowvol.cli.compare
import shadowvol.cli.demo
import shadowvol.cli.planar
import shadowvol.cli.raytrace
import shadowvol.cli.render
import shadowvol.compare.estimate
import shadowvol.io
import shadowvol.raster.estimate
import shadowvol.raster.renderer
import shadowvol.scenefile
from shadowvol import memory
from shadowvol.cli import status
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.course import raytree_slide
from shadowvol.course.slides import Layout
from shadowvol.errors import InputError
from shadowvol.raster import target
from shadowvol.scene import MAX_IMAGE_PIXELS, SceneError
from shadowvol.scenefile import load_scene, save_scene

GIB = 1 << 30


def _scene(tmp_path, name="cage.toml", width=32, height=24):
    path = tmp_path / f"{name.split('.')[0]}.json"
    save_scene(load_scene(SCENES / name).replace(width=width, height=height), path)
    return path


def _one_error_line(err: str) -> str:
    """The one `error:` line of stderr (progress and summaries may come before it)."""
    lines = [line for line in err.splitlines() if line.startswith("error")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def _nothing_written(folder, but=()):
    """No file in `folder` (recursively) except the inputs and `but`, and no temporary."""
    left = sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                  if p.is_file() and p.suffix not in (".json", ".toml", ".jsonl")
                  and p.name not in but)
    assert not left, f"written although the command failed: {left}"


# ---- the budget ---------------------------------------------------------------------------------

@pytest.mark.parametrize("text, value", [("12GiB", 12 * GIB), ("12G", 12 * GIB), ("12 gb", 12e9),
                                         ("500MiB", 500 << 20), ("1.5GiB", 1.5 * GIB),
                                         ("2000000000", 2e9), ("64k", 64 << 10)])
def test_a_budget_is_a_size(text, value):
    assert memory.parse_size(text) == int(value)


@pytest.mark.parametrize("text", ["", "lots", "-1GiB", "0", "12 GiBs", "1e9", "12 PiB"])
def test_a_bad_budget_names_the_variable(text):
    with pytest.raises(InputError, match=r"SHADOWVOL_MEMORY_BUDGET: expected a memory size"):
        memory.parse_size(text)


def test_the_default_budget_is_three_quarters_of_the_machine(monkeypatch):
    monkeypatch.delenv(memory.ENV, raising=False)
    assert memory.budget() == int(0.75 * memory.machine_memory())
    physical = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    assert 0 < memory.machine_memory() <= physical
    monkeypatch.setenv(memory.ENV, "3GiB")
    assert memory.budget() == 3 * GIB
    assert memory.budget("1GiB") == GIB            # an argument wins over the variable
    assert memory.budget(123456789) == 123456789


def test_each_renderer_estimates_from_its_own_numbers(monkeypatch):
    """The estimates read the numbers of the code they count (no copies): the GL frame's bytes
    and the lit bits' pages of `target`, the tiles of the masks, Whitted and the path tracer."""
    monkeypatch.setattr(memory, "threads", lambda: 3)
    scene = load_scene(SCENES / "cage.toml").replace(width=100, height=10)
    lights = (scene.lights[0],) * (target.LIGHTS_PER_PAGE + 1)   # two pages of lit bits
    terms = dict(shadowvol.raster.estimate.render(scene.replace(lights=lights)).terms)
    assert terms["GL frame"] == target.BYTES_PER_PIXEL * 1000
    assert terms["lit bits (uint32 per page)"] == 4 * 2 * 1000
    tiles = dict(raytrace.estimate.masks(scene).terms)["tiles in flight"]
    assert tiles == 3 * raytrace.masks.MASK_TILE_RAYS * raytrace.estimate.MASK_RAY_BYTES
    tiles = dict(raytrace.outlook.estimate.whitted(scene).terms)["tiles in flight"]
    assert tiles == (3 * raytrace.outlook.whitted.TILE_RAYS
                     * raytrace.outlook.estimate.WHITTED_RAY_BYTES)
    tiles = dict(raytrace.outlook.estimate.path_traced(scene, 1).terms)["tiles in flight"]
    assert tiles == (3 * raytrace.outlook.path.pathtrace.TILE_PATHS
                     * raytrace.outlook.estimate.PATH_RAY_BYTES)


def test_reasonable_images_fit_a_small_machine():
    """What a user would reasonably render needs far less than a laptop has: a 4K frame with
    every output, and the old 64-Mpixel maximum (which took 10 GB) within the default budget
    of a 16 GB machine (12 GiB)."""
    scene = load_scene(SCENES / "stack.toml").replace(width=3840, height=2160)
    every = ("image", "lit", "coverage", "depth", "distance", "normal", "object_id", "facing",
             "casters")
    assert shadowvol.raster.estimate.render(scene, every, written=("png", "masks")).total \
        < 3 * GIB
    assert raytrace.estimate.masks(scene, every[3:]).total < 3 * GIB
    assert raytrace.outlook.estimate.whitted(scene, ("png", "exr")).total < 2 * GIB
    assert shadowvol.compare.estimate.compare(scene).total < 4 * GIB
    big = scene.replace(width=8192, height=8192)
    memory.check(shadowvol.raster.estimate.render(big), "12GiB")
    memory.check(raytrace.outlook.estimate.whitted(big), "12GiB")


def test_the_cap_stays_above_any_budget_here():
    assert MAX_IMAGE_PIXELS == 16384 * 16384
    with pytest.raises(SceneError, match=r"image: 16385x16384 is more than 268435456 pixels"):
        load_scene(SCENES / "cage.toml").replace(width=16385, height=16384)


def _boom(*args, **kwargs):
    raise AssertionError("the render was started although the image is over the budget")


OVER_BUDGET = {  # command -> (argv, what must not run)
    "shadowvol render": (["render", "S", "-o", "O/x.png", "--masks"],
                         (shadowvol.cli.render, "Renderer")),
    "shadowvol compare": (["compare", "S", "-o", "O/x.png"], (shadowvol.cli.compare, "compare")),
    "shadowvol planar": (["planar", "P", "-o", "O/x.png"],
                         (shadowvol.cli.planar, "render_planar")),
    "raytrace render": (["render", "S", "-o", "O/x.png", "--no-progress"],
                        (shadowvol.cli.raytrace.render, "render")),
    "raytrace masks": (["masks", "S", "-o", "O/x.npz"],
                       (shadowvol.cli.raytrace.masks, "shadow_masks")),
    "raytrace masks --outputs": (["masks", "S", "-o", "O/x.npz", "--outputs", "all"],
                                 (shadowvol.cli.raytrace.masks, "ground_truth")),
    "raytrace path": (["render", "S", "-o", "O/x.png", "--integrator", "path", "--spp", "4"],
                      (raytrace.outlook.path.pathtrace, "render")),
    "raytrace radiosity": (["radiosity", "S", "-o", "O/x.png"],
                           (raytrace.outlook.radiosity, "solve")),
    "raytrace tree": (["tree", "S", "--pixel", "3", "3", "-o", "O/x.png"],
                      (shadowvol.cli.raytrace.tree, "ray_tree")),
}


def _slide_image(path) -> tuple[int, int]:
    """(width, height) the ray tree slide traces for the scene at `path`."""
    traced = raytree_slide.traced_scene(Layout(supersample=1), load_scene(path))
    return traced.width, traced.height


@pytest.mark.gl
@pytest.mark.parametrize("command", sorted(OVER_BUDGET))
@pytest.mark.parametrize("how", ["option", "variable"])
def test_an_image_over_the_budget_is_refused_before_rendering(command, how, tmp_path,
                                                              monkeypatch, capsys):
    scene = _scene(tmp_path, width=4000, height=3000)
    planar = _scene(tmp_path, "planar.toml", width=4000, height=3000)
    argv, (module, name) = OVER_BUDGET[command]
    monkeypatch.setattr(module, name, _boom)
    out = tmp_path / "out"
    out.mkdir()
    names = {"S": str(scene), "P": str(planar)}
    argv = [names.get(a, a).replace("O/", f"{out}/") for a in argv]
    if how == "option":
        argv += ["--memory-budget", "64MiB"]
    else:
        monkeypatch.setenv(memory.ENV, "64MiB")
    main = shadowvol_main if command.startswith("shadowvol") else raytrace_main
    assert main(argv) == status.BAD_INPUT
    line = _one_error_line(capsys.readouterr().err)
    shown = planar if "planar" in command else scene
    # the tree draws the slide: its image is the slide's panel, whatever the scene's size
    size = ("x".join(map(str, _slide_image(scene))) if command == "raytrace tree"
            else "4000x3000")
    assert re.fullmatch(
        rf"error: {re.escape(str(shown))}: image: {size} needs about [\d.]+ [MG]iB for .+ "
        r"\(model: .+ B/px.*\), more than the memory budget of 64 MiB \(set "
        r"SHADOWVOL_MEMORY_BUDGET, e\.g\. 32GiB, or --memory-budget to change it\)", line), line
    _nothing_written(out)


@pytest.mark.gl
def test_the_tree_slide_is_judged_by_the_image_it_traces(tmp_path, monkeypatch):
    """A 4000x3000 scene's Whitted image is over 512 MiB, the slide's panel is not: the tree
    command goes on to trace (and is stopped there), it is not refused for the scene's size."""
    scene = _scene(tmp_path, width=4000, height=3000)
    assert raytrace.outlook.estimate.whitted(load_scene(scene)).total + memory.BASE \
        > 512 * 2**20
    monkeypatch.setattr(shadowvol.cli.raytrace.tree, "ray_tree", _boom)
    with pytest.raises(AssertionError, match="the render was started"):
        raytrace_main(["tree", str(scene), "--pixel", "3", "3", "-o", str(tmp_path / "x.png"),
                       "--memory-budget", "512MiB"])


@pytest.mark.gl
def test_within_the_budget_it_renders_and_a_bad_budget_is_bad_input(tmp_path, capsys):
    scene = _scene(tmp_path, width=64, height=48)
    assert shadowvol_main(["render", str(scene), "-o", str(tmp_path / "x.png"),
                           "--memory-budget", "1GiB"]) == status.OK
    assert raytrace_main(["masks", str(scene), "-o", str(tmp_path / "x.npz"),
                          "--memory-budget", "1GiB"]) == status.OK
    capsys.readouterr()
    assert shadowvol_main(["render", str(scene), "-o", str(tmp_path / "y.png"),
                           "--memory-budget", "plenty"]) == status.BAD_INPUT
    assert "--memory-budget: expected a memory size" in _one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "y.png").exists()


@pytest.mark.gl
def test_a_bad_budget_in_the_environment_is_named_as_the_variable(tmp_path, capsys, monkeypatch):
    scene = _scene(tmp_path, width=64, height=48)
    monkeypatch.setenv("SHADOWVOL_MEMORY_BUDGET", "plenty")
    assert shadowvol_main(["render", str(scene), "-o", str(tmp_path / "y.png")]) == \
        status.BAD_INPUT
    assert "SHADOWVOL_MEMORY_BUDGET: expected a memory size" in \
        _one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "y.png").exists()


# ---- out of memory in every command ------------------------------------------------------------

def _no_memory(*args, **kwargs):
    # numpy's own words
    raise MemoryError("Unable to allocate 3.00 GiB for an array with shape (20000, 20000) "
                      "and data type float64")


class _NoViewer:
    def __init__(self, scene):
        _no_memory()


OUT_OF_MEMORY = {  # command -> (tool, argv, [(module, name)] to fail, "while ...")
    "render": ("shadowvol", ["render", "S", "-o", "O/x.png", "--masks"],
               [(shadowvol.raster.renderer.Renderer, "render")], "while rendering ("),
    "render, writing": ("shadowvol", ["render", "S", "-o", "O/x.png"],
                        [(shadowvol.io, "png_bytes")], "while writing O/x.png ("),
    "render, masks": ("shadowvol", ["render", "S", "-o", "O/x.png", "--masks", "O/m.npz"],
                      [(shadowvol.io, "npz_bytes")], "while writing O/m.npz ("),
    "render, reading": ("shadowvol", ["render", "S", "-o", "O/x.png"],
                        [(shadowvol.scenefile, "scene_from_dict")], "while reading S ("),
    "compare": ("shadowvol", ["compare", "S", "-o", "O/x.png"],
                [(shadowvol.raster.renderer.Renderer, "render")], "while rendering ("),
    "planar": ("shadowvol", ["planar", "P", "-o", "O/x.png"],
               [(shadowvol.cli.planar, "render_planar")], "while rendering ("),
    "demo": ("shadowvol", ["demo", "--small", "-o", "O/g"],
             [(shadowvol.cli.demo, "build_gallery")], "while rendering ("),
    "shadow2d": ("shadowvol", ["shadow2d", "--example", "-o", "O/x.png", "--size", "64"],
                 [(shadowvol.io, "png_bytes")], "while writing O/x.png ("),
    "batch": ("shadowvol", ["batch", "J", "-o", "O/b"],
              [(shadowvol.raster.renderer.Renderer, "render")],
              "while rendering ("),  # the frame is named first: cage/000000
    "view": ("shadowvol", ["view", "S"], [], "while rendering ("),
    "raytrace render": ("raytrace", ["render", "S", "-o", "O/x.png", "--no-progress"],
                        [(raytrace.outlook.whitted, "trace")], "while rendering ("),
    "raytrace render, writing": ("raytrace", ["render", "S", "-o", "O/x.png", "--exr", "O/x.exr",
                                              "--no-progress"],
                                 [(shadowvol.io, "exr_bytes")], "while writing O/x.exr ("),
    "raytrace masks": ("raytrace", ["masks", "S", "-o", "O/x.npz"],
                       [(raytrace.masks, "_tile_masks")], "while rendering ("),
    "raytrace masks --outputs": ("raytrace", ["masks", "S", "-o", "O/x.npz", "--outputs", "all"],
                                 [(shadowvol.cli.raytrace.masks, "ground_truth")],
                                 "while rendering ("),
    "raytrace tree": ("raytrace", ["tree", "S", "--pixel", "3", "3", "-o", "O/x.png"],
                      [(shadowvol.cli.raytrace.tree, "ray_tree")], "while rendering ("),
    "raytrace exercise": ("raytrace", ["exercise", "plane", "-o", "O/x.png"],
                          [(raytrace.exercise, "solve_plane")], "while rendering ("),
    "raytrace path": ("raytrace", ["render", "R", "-o", "O/x.png", "--integrator", "path",
                                   "--spp", "1", "--no-progress"],
                      [(raytrace.outlook.path.pathtrace, "trace_rows")], "while rendering ("),
    "raytrace radiosity": ("raytrace", ["radiosity", "R", "-o", "O/x.png", "--level", "0",
                                        "--rays", "8"],
                           [(raytrace.outlook.radiosity, "display")], "while rendering ("),
}


@pytest.mark.gl
@pytest.mark.parametrize("command", sorted(OUT_OF_MEMORY))
def test_out_of_memory_in_every_command_is_one_line_and_status_3(command, tmp_path,
                                                                 monkeypatch, capsys):
    tool, argv, failing, expected = OUT_OF_MEMORY[command]
    scene = _scene(tmp_path)
    planar = _scene(tmp_path, "planar.toml")
    box = _scene(tmp_path, "cornell.toml", 16, 16)
    jobs = tmp_path / "jobs.jsonl"
    jobs.write_text('{"scene": "cage.json", "size": [16, 12], "cameras": [{"eye": [4, 3, 5], '
                    '"target": [0, 1, 0]}], "outputs": ["image"]}\n')
    out = tmp_path / "out"
    out.mkdir()
    names = {"S": str(scene), "P": str(planar), "R": str(box), "J": str(jobs)}

    def fill(a):
        a = names.get(a, a)
        return a.replace("O/", f"{out}/")

    argv = [fill(a) for a in argv]
    for module, name in failing:
        monkeypatch.setattr(module, name, _no_memory)
    if command == "view":
        monkeypatch.setenv("DISPLAY", ":99")
        monkeypatch.setitem(sys.modules, "shadowvol.view.app",
                            types.SimpleNamespace(Viewer=_NoViewer))
    main = shadowvol_main if tool == "shadowvol" else raytrace_main
    assert main(argv) == status.RENDER_FAILED
    line = _one_error_line(capsys.readouterr().err)
    frame = "cage/000000: " if command == "batch" else ""
    assert line.startswith(f"error: {frame}out of memory " + _fill_all(expected, names, out)), \
        line
    assert line.endswith("; try a smaller image or fewer triangles"), line
    # a file written before the one that failed is complete (each is atomic); the rest never
    # appear (the .npz after the image, as docs/robustness.md says of Ctrl-C)
    done = {"render, masks": ["x.png"], "raytrace render, writing": ["x.png"]}.get(command, [])
    _nothing_written(out, but=done)
    for name in done:
        assert shadowvol.io.Image.open(out / name).size == (32, 24)


def _fill_all(text: str, names: dict, out) -> str:
    for key, value in names.items():
        text = text.replace(f" {key} ", f" {value} ")
    return text.replace("O/", f"{out}/")


@pytest.mark.gl
def test_a_gl_out_of_memory_is_status_3_and_no_frame_is_written(tmp_path, monkeypatch, capsys):
    """moderngl raises nothing when the driver cannot allocate a buffer: the GL error flag
    says GL_OUT_OF_MEMORY and the frame would be wrong.  (llvmpipe refuses a 1 TiB buffer.)"""
    render = shadowvol.raster.renderer.Renderer.render

    def render_and_overflow(self, *args, **kwargs):
        result = render(self, *args, **kwargs)
        self.ctx.buffer(reserve=1 << 40).release()
        return result

    monkeypatch.setattr(shadowvol.raster.renderer.Renderer, "render", render_and_overflow)
    scene = _scene(tmp_path)
    code = shadowvol_main(["render", str(scene), "-o", str(tmp_path / "x.png")])
    line = _one_error_line(capsys.readouterr().err)
    assert code == status.RENDER_FAILED
    assert line == ("error: out of memory while rendering (the GL reported GL_OUT_OF_MEMORY); "
                    "try a smaller image or fewer triangles")
    assert not (tmp_path / "x.png").exists()


# ---- a real limit: a process whose address space is too small ----------------------------------

CHILD = textwrap.dedent("""
    import resource, sys
    from shadowvol.cli import shadowvol_entry, raytrace_entry
    entry = shadowvol_entry if sys.argv[1] == "shadowvol" else raytrace_entry
    args = sys.argv[2:]
    assert entry([a.replace("big", "small") for a in args]) == 0  # it works
    limit = int(open("/proc/self/status").read().split("VmSize:")[1].split()[0]) * 1024
    limit += 400 << 20  # 400 MiB more than it has: too little for the big image
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    sys.exit(entry(args))
    """)


@pytest.mark.gl
@pytest.mark.parametrize("tool, argv", [
    ("shadowvol", ["render", "SCENE", "-o", "OUT"]),
    ("raytrace", ["render", "SCENE", "-o", "OUT", "--no-progress", "--max-depth", "0"]),
])
def test_under_an_address_space_limit(tool, argv, tmp_path):
    """A real MemoryError (RLIMIT_AS: `ulimit -v`), with the budget set out of the way: one
    line, status 3, no file."""
    save_scene(load_scene(SCENES / "cage.toml").replace(width=8192, height=8192),
               tmp_path / "big.json")
    save_scene(load_scene(SCENES / "cage.toml").replace(width=64, height=48),
               tmp_path / "small.json")
    argv = [a.replace("SCENE", str(tmp_path / "big.json")).replace("OUT", str(tmp_path / "big.png"))
            for a in argv]
    done = subprocess.run([sys.executable, "-c", CHILD, tool, *argv], cwd=ROOT,
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, memory.ENV: "1TiB"})
    assert done.returncode == status.RENDER_FAILED, done.stderr
    line = _one_error_line(done.stderr.replace(f"wrote {tmp_path / 'small.png'}", ""))
    assert re.match(r"error: (out of memory while (rendering|writing \S+) \(Unable to allocate"
                    r"|the GL could not allocate a 8192x8192 frame)", line), line
    assert {p.name for p in tmp_path.iterdir()} == {"big.json", "small.json", "small.png"}


def test_numpy_allocation_error_is_a_memory_error():
    """What the tests above fake is what numpy raises."""
    with pytest.raises(MemoryError, match="Unable to allocate"):
        np.empty(1 << 62, np.uint8)


@pytest.mark.parametrize("how", ["option", "variable"])
def test_demo_slides_over_the_budget_are_refused_before_rendering(how, tmp_path, monkeypatch,
                                                                  capsys):
    """`shadowvol demo --size`: each example scene is estimated as `compare` of it at the slide
    size; over the budget, one line naming the scene and exit 2, before any picture."""
    import shadowvol.course.gallery
    monkeypatch.setattr(shadowvol.course.gallery, "DEMOS", (_boom,))
    out = tmp_path / "out"
    argv = ["demo", "-o", str(out), "--size", "4000x3000"]
    if how == "option":
        argv += ["--memory-budget", "64MiB"]
    else:
        monkeypatch.setenv(memory.ENV, "64MiB")
    assert shadowvol_main(argv) == status.BAD_INPUT
    line = _one_error_line(capsys.readouterr().err)
    assert re.fullmatch(r"error: .+\.toml: image: 4000x3000 needs about [\d.]+ [MG]iB for "
                        r"shadowvol compare \(model: .+\), more than the memory budget of "
                        r"64 MiB .+", line), line
    assert not out.exists() or not any(out.iterdir())
