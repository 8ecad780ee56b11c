"""One exit-status table (shadowvol.cli.status) for every command of both tools: each command
is driven into each class it can reach, and every --help prints the table."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
from builders import ROOT, SCENES

import shadowvol.batch
import shadowvol.cli.compare
import shadowvol.cli.raytrace
import shadowvol.cli.render
import shadowvol.course.gallery
import shadowvol.raster.renderer
from shadowvol.cli import status
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main
from shadowvol.errors import InputError
from shadowvol.raster.platform.context import ContextError
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene, save_scene

pytestmark = pytest.mark.gl  # the OK cases render


@pytest.fixture
def small(tmp_path):
    path = tmp_path / "cage.json"
    save_scene(load_scene(SCENES / "cage.toml").replace(width=32, height=24), path)
    return path


def _no_gl(*args, **kwargs):
    raise ContextError("cannot create a headless EGL context (blocked by the test)")


def _no_memory(*args, **kwargs):
    raise MemoryError()


SHADOWVOL_OK = {
    "render": lambda s, o: ["render", str(s), "-o", str(o / "x.png")],
    "compare": lambda s, o: ["compare", str(s), "-o", str(o / "x.png")],
    "shadow2d": lambda s, o: ["shadow2d", "--example", "-o", str(o / "x.png"), "--size", "64"],
}
RAYTRACE_OK = {
    "render": lambda s, o: ["render", str(s), "-o", str(o / "x.png"), "--no-progress"],
    "masks": lambda s, o: ["masks", str(s), "-o", str(o / "x.npz")],
    "tree": lambda s, o: ["tree", str(s), "--pixel", "16", "12", "--depth", "1", "-o",
                          str(o / "x.png")],
}


@pytest.mark.parametrize("command", sorted(SHADOWVOL_OK))
def test_shadowvol_ok_and_bad_input(command, small, tmp_path, capsys):
    assert shadowvol_main(SHADOWVOL_OK[command](small, tmp_path)) == status.OK
    bad = [a.replace(str(small), str(tmp_path / "missing.toml")) for a in
           SHADOWVOL_OK[command](small, tmp_path)]
    if command == "shadow2d":
        bad = ["shadow2d", str(tmp_path / "missing.toml")]
    assert shadowvol_main(bad) == status.BAD_INPUT
    wrong_suffix = [a.replace("x.png", "x.jpg") for a in SHADOWVOL_OK[command](small, tmp_path)]
    assert shadowvol_main(wrong_suffix) == status.BAD_INPUT
    assert not (tmp_path / "x.jpg").exists()
    err = capsys.readouterr().err
    assert "Traceback" not in err and "must end in .png" in err


@pytest.mark.parametrize("command", sorted(RAYTRACE_OK))
def test_raytrace_ok_bad_input_and_failure(command, small, tmp_path, capsys, monkeypatch):
    assert raytrace_main(RAYTRACE_OK[command](small, tmp_path)) == status.OK
    bad = [a.replace(str(small), str(tmp_path / "missing.toml")) for a in
           RAYTRACE_OK[command](small, tmp_path)]
    assert raytrace_main(bad) == status.BAD_INPUT
    monkeypatch.setattr(getattr(shadowvol.cli.raytrace, command), "load_scene", _no_memory)
    assert raytrace_main(RAYTRACE_OK[command](small, tmp_path)) == status.RENDER_FAILED
    err = capsys.readouterr().err
    assert "Traceback" not in err and "error: out of memory" in err


def test_compare_over_budget():
    args = ["compare", str(SCENES / "inside_shadow.toml"), "--size", "80x60", "--method",
            "zpass", "--max-interior", "0", "-o"]
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        assert shadowvol_main(args + [f"{d}/c.png"]) == status.OVER_BUDGET


@pytest.mark.parametrize("command, module", [("render", shadowvol.cli.render),
                                             ("compare", shadowvol.compare.comparison),
                                             ("demo", shadowvol.course.gallery)])
def test_no_gl_is_rendering_failed(command, module, small, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(module, "create_context", _no_gl)
    args = {"render": ["render", str(small), "-o", str(tmp_path / "x.png")],
            "compare": ["compare", str(small), "-o", str(tmp_path / "x.png")],
            "demo": ["demo", "--small", "-o", str(tmp_path / "g")]}[command]
    assert shadowvol_main(args) == status.RENDER_FAILED
    assert capsys.readouterr().err.startswith("error: cannot create a headless EGL context")
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "g").exists()


def test_demo_bad_scenes_folder(tmp_path):
    assert shadowvol_main(["demo", "-o", str(tmp_path / "g"), "--scenes",
                           str(tmp_path / "nowhere")]) == status.BAD_INPUT


BLOCK = textwrap.dedent("""
    import sys
    class Block:
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] == MISSING:
                raise ImportError("No module named " + repr(name), name=name)
    sys.meta_path.insert(0, Block())
    """)


@pytest.mark.parametrize("missing, tool, args, pip", [
    ("pyrender", "shadowvol.cli.main", ["compare", "SCENE", "--pyrender", "-o", "OUT.png"],
     "pip install 'shadowvol[peer]'"),
    ("embreex", "shadowvol.cli.raytrace", ["masks", "SCENE", "-o", "OUT.npz"],
     "pip install embreex"),
])
def test_a_missing_extra_is_bad_input_naming_the_pip_command(missing, tool, args, pip, small,
                                                              tmp_path):
    args = [a.replace("SCENE", str(small)).replace("OUT", str(tmp_path / "out")) for a in args]
    code = BLOCK.replace("MISSING", repr(missing)) + \
        f"from {tool} import main\nsys.exit(main({args!r}))\n"
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == status.BAD_INPUT, done.stderr
    assert pip in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr  # one line, nothing else
    assert not list(tmp_path.glob("out*"))


@pytest.mark.parametrize("argv", [["--help"], ["render", "--help"], ["compare", "--help"],
                                  ["demo", "--help"], ["shadow2d", "--help"],
                                  ["planar", "--help"]])
def test_every_shadowvol_help_prints_the_table(argv, capsys):
    with pytest.raises(SystemExit):
        shadowvol_main(argv)
    text = " ".join(capsys.readouterr().out.split())
    assert " ".join(status.EPILOG.split()) in text


@pytest.mark.parametrize("argv", [["--help"], ["exercise", "--help"]])
def test_raytrace_help_prints_the_table(argv, capsys):
    with pytest.raises(SystemExit):
        raytrace_main(argv)
    assert " ".join(status.EPILOG.split()) in " ".join(capsys.readouterr().out.split())


# ---- the commands that came later: every one into the classes it can reach -------------------

def _radiosity_scene(tmp_path):
    path = tmp_path / "box.json"
    save_scene(load_scene(SCENES / "cornell.toml").replace(width=16, height=16), path)
    return path


@pytest.mark.parametrize("argv, ok", [
    (lambda s, o: ["planar", str(SCENES / "planar.toml"), "-o", str(o / "x.png")], True),
    (lambda s, o: ["planar", str(s), "-o", str(o / "x.png"), "--receiver", "no such"], False),
    (lambda s, o: ["planar", str(o / "missing.toml"), "-o", str(o / "x.png")], False),
    (lambda s, o: ["planar", str(s), "-o", str(o / "x.gif")], False),
    (lambda s, o: ["batch", str(o / "missing.jsonl"), "-o", str(o / "out")], False),
])
def test_planar_and_batch(argv, ok, small, tmp_path, capsys):
    code = shadowvol_main(argv(small, tmp_path))
    assert code == (status.OK if ok else status.BAD_INPUT)
    if not ok:
        err = capsys.readouterr().err
        assert err.startswith("error: ") and "Traceback" not in err


def test_batch_ok_and_a_frame_that_fails_to_render(small, tmp_path, monkeypatch):
    jobs = tmp_path / "jobs.jsonl"
    jobs.write_text('{"scene": "cage.json", "size": [16, 12], "cameras": [{"eye": [4, 3, 5], '
                    '"target": [0, 1, 0]}], "outputs": ["image"]}\n')
    assert shadowvol_main(["batch", str(jobs), "-o", str(tmp_path / "ok")]) == status.OK
    monkeypatch.setattr(shadowvol.raster.renderer.Renderer, "render", _no_memory)
    assert shadowvol_main(["batch", str(jobs), "-o", str(tmp_path / "fail")]) == \
        status.RENDER_FAILED


# A flag that cannot be used, and a scene file that cannot be read: each its own class (the
# command line's InputError, the scene's SceneError), both status 2 in one line.
BAD_FLAGS = {
    "suffix": (shadowvol_main, ["render", "S", "-o", "O/x.jpg"], "-o: 'O/x.jpg' must end in .png"),
    "budget": (shadowvol_main, ["render", "S", "-o", "O/x.png", "--memory-budget", "lots"],
               "--memory-budget: expected a memory size"),
    "size": (shadowvol_main, ["compare", "S", "-o", "O/x.png", "--size", "99999999x5"],
             "--size: 99999999x5 is more than"),
    "pixel": (raytrace_main, ["tree", "S", "--pixel", "99", "0", "-o", "O/x.png"],
              "--pixel: 99 0 is outside the 32x24"),
    "spp": (raytrace_main, ["render", "S", "-o", "O/x.png", "--integrator", "path", "--spp", "0"],
            "--spp: must be >= 1, got 0"),
}


def _raised(monkeypatch) -> list:
    """The exceptions the commands report from now on."""
    raised, report = [], status.report
    monkeypatch.setattr(status, "report", lambda exc, *a: raised.append(exc) or report(exc, *a))
    return raised


@pytest.mark.parametrize("case", BAD_FLAGS)
def test_a_bad_flag_is_an_input_error(case, small, tmp_path, capsys, monkeypatch):
    tool, argv, words = BAD_FLAGS[case]
    raised = _raised(monkeypatch)
    fill = {"S": str(small), "O/x.jpg": f"{tmp_path}/x.jpg", "O/x.png": f"{tmp_path}/x.png"}
    assert tool([fill.get(a, a) for a in argv]) == status.BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: " + words.replace("O/", f"{tmp_path}/"))
    assert [type(exc) for exc in raised] == [InputError], raised


def test_a_bad_scene_file_is_a_scene_error_and_a_bad_batch_option_an_input_error(
        tmp_path, capsys, monkeypatch):
    raised = _raised(monkeypatch)
    (tmp_path / "bad.toml").write_text("[camera]\neye = [0, 1]\n")
    assert shadowvol_main(["render", str(tmp_path / "bad.toml"), "-o",
                           str(tmp_path / "x.png")]) == status.BAD_INPUT
    assert [type(exc) for exc in raised] == [SceneError], raised
    assert capsys.readouterr().err.startswith(f"error: {tmp_path / 'bad.toml'}: ")
    with pytest.raises(InputError, match="^--workers: must be a whole number >= 1, got 0$"):
        shadowvol.batch.run([], tmp_path / "out", workers=0)


def test_view_without_a_display_is_bad_input(small, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert shadowvol_main(["view", str(small)]) == status.BAD_INPUT


@pytest.mark.parametrize("argv, code", [
    (["exercise", "plane"], status.OK),
    (["exercise", "tir"], status.OK),
    (["exercise", "plane", "-o", "x.jpg"], status.BAD_INPUT),
])
def test_raytrace_exercise(argv, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert raytrace_main(argv) == code


def test_raytrace_radiosity_and_path_tracing(tmp_path, monkeypatch, capsys):
    box = _radiosity_scene(tmp_path)
    assert raytrace_main(["radiosity", str(box), "--level", "0", "--rays", "8", "-o",
                          str(tmp_path / "r.png")]) == status.OK
    assert raytrace_main(["radiosity", str(box), "--level", "-1", "-o",
                          str(tmp_path / "r.png")]) == status.BAD_INPUT
    assert raytrace_main(["render", str(box), "--integrator", "path", "--spp", "1",
                          "--no-progress", "-o", str(tmp_path / "p.png")]) == status.OK
    assert raytrace_main(["render", str(box), "--integrator", "path", "--spp", "0",
                          "-o", str(tmp_path / "p.png")]) == status.BAD_INPUT
    monkeypatch.setattr(shadowvol.cli.raytrace.radiosity, "load_scene", _no_memory)
    assert raytrace_main(["radiosity", str(box), "-o", str(tmp_path / "r.png")]) == \
        status.RENDER_FAILED
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["planar", "--help"], ["view", "--help"], ["batch", "--help"]])
def test_the_later_commands_print_the_table(argv, capsys):
    with pytest.raises(SystemExit):
        shadowvol_main(argv)
    assert " ".join(status.EPILOG.split()) in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("argv", [["exercise", "--help"], ["radiosity", "--help"],
                                  ["render", "--help"], ["masks", "--help"], ["tree", "--help"]])
def test_every_raytrace_help_prints_the_table(argv, capsys):
    with pytest.raises(SystemExit):
        raytrace_main(argv)
    assert " ".join(status.EPILOG.split()) in " ".join(capsys.readouterr().out.split())
