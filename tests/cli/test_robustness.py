"""Robustness of the command line and of the files it writes (docs/robustness.md):

* several scenes in one `shadowvol render` call: each writes OUTDIR/NAME.png; a bad one is
  reported and the others still render; the exit status is the highest of any scene;
* exit statuses: 0 ok, 2 bad input, 3 rendering failed;
* outputs are atomic: an error or Ctrl-C while writing leaves no file and no temporary, and an
  existing file as it was;
* a scene cannot choose where its output goes (names from the file name, sanitised).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.render import safe_name
from shadowvol.frame import save_masks
from shadowvol.io import atomic_write, save_png
from shadowvol.primitives import box, plane
from shadowvol.scene import Camera, PointLight, Scene
from shadowvol.scenefile import save_scene

pytestmark = pytest.mark.gl  # renders through the CLI in this process


def small_scene(name="small") -> Scene:
    return Scene(camera=Camera(eye=[0, 3, 5], target=[0, 0, 0]),
                 objects=[plane("floor", size=[6, 6]), box("b", [0, 0.5, 0], [1, 1, 1])],
                 lights=[PointLight([1, 4, 1])], width=32, height=24, name=name)


def leftovers(folder: Path) -> list[str]:
    """Temporary files atomic_write might have left (".NAME.*.part")."""
    return sorted(p.name for p in folder.rglob("*.part"))


# ---- several scenes ----------------------------------------------------------------------------

def test_several_scenes_one_bad_the_others_render(tmp_path, capsys):
    good1, good2 = tmp_path / "one.json", tmp_path / "two.json"
    save_scene(small_scene(), good1)
    save_scene(small_scene(), good2)
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera]\neye = [0, 0]\n")
    out = tmp_path / "out"
    code = shadowvol_main(["render", str(good1), str(bad), str(good2), "-o", str(out), "--masks"])
    err = capsys.readouterr().err
    assert code == 2
    assert sorted(p.name for p in out.iterdir()) == ["one-masks.npz", "one.png",
                                                     "two-masks.npz", "two.png"]
    assert f"error: {bad}" in err and "Traceback" not in err
    assert err.count("error:") == 1


def test_same_file_names_do_not_overwrite_each_other(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    save_scene(small_scene(), tmp_path / "a" / "s.json")
    save_scene(small_scene(), tmp_path / "b" / "s.json")
    out = tmp_path / "out"
    assert shadowvol_main(["render", str(tmp_path / "a" / "s.json"), str(tmp_path / "b" / "s.json"),
                     "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["s-2.png", "s.png"]


def test_a_scene_cannot_choose_where_its_output_goes(tmp_path):
    """The name inside the scene never becomes a path; the file name is reduced to safe
    characters; nothing is written outside -o."""
    scene = tmp_path / "in" / "we ird;$(rm -rf).json"
    scene.parent.mkdir()
    save_scene(small_scene(name="../../../escaped"), scene)
    out = tmp_path / "out"
    assert shadowvol_main(["render", str(scene), str(scene), "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["we_ird_rm_-rf_-2.png", "we_ird_rm_-rf_.png"]
    assert not list(tmp_path.rglob("escaped*"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in", "out"]
    assert safe_name("..hidden") == "hidden" and safe_name("/") == "_"
    assert safe_name("") == "scene"


def test_several_scenes_want_a_directory(tmp_path, capsys):
    save_scene(small_scene(), tmp_path / "s.json")
    code = shadowvol_main(["render", str(tmp_path / "s.json"), str(tmp_path / "s.json"),
                     "-o", str(tmp_path / "x.png")])
    assert code == 2 and "must name a directory" in capsys.readouterr().err
    code = shadowvol_main(["render", str(tmp_path / "s.json"), str(tmp_path / "s.json"),
                     "-o", str(tmp_path / "d"), "--masks", "m.npz"])
    assert code == 2 and "takes no file name" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "d").exists()


def test_one_scene_with_a_masks_flag_alone_writes_beside_the_image(tmp_path):
    save_scene(small_scene(), tmp_path / "s.json")
    assert shadowvol_main(["render", str(tmp_path / "s.json"), "-o", str(tmp_path / "img.png"),
                     "--masks"]) == 0
    with np.load(tmp_path / "img-masks.npz", allow_pickle=False) as data:
        assert data["lit"].shape == (1, 24, 32)


# ---- exit statuses -----------------------------------------------------------------------------

def test_exit_statuses_are_documented_in_help(capsys):
    with pytest.raises(SystemExit):
        shadowvol_main(["--help"])
    text = capsys.readouterr().out
    for words in ("0 success", "1 a comparison over its budget", "2 bad input",
                  "3 rendering failed"):
        assert words in " ".join(text.split())
    with pytest.raises(SystemExit):
        shadowvol_main(["render", "--help"])
    assert "3 rendering failed" in " ".join(capsys.readouterr().out.split())


def test_out_of_memory_is_status_3_with_a_message(tmp_path, capsys, monkeypatch):
    import shadowvol.raster.renderer

    def no_memory(*args, **kwargs):
        raise MemoryError()

    monkeypatch.setattr(shadowvol.raster.renderer.Renderer, "render", no_memory)
    save_scene(small_scene(), tmp_path / "s.json")
    code = shadowvol_main(["render", str(tmp_path / "s.json"), "-o", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert code == 3 and err.startswith("error: out of memory") and "Traceback" not in err
    assert not (tmp_path / "x.png").exists()


def test_an_image_too_big_is_bad_input(tmp_path, capsys):
    """Beyond Scene.MAX_IMAGE_PIXELS (16384 x 16384) the loader refuses; beyond the GL's largest
    renderbuffer the command refuses before allocating anything."""
    data = json.loads((lambda p: (save_scene(small_scene(), p), p.read_text())[1])(
        tmp_path / "s.json"))
    data["image"].update(width=100000, height=100000)
    (tmp_path / "huge.json").write_text(json.dumps(data))
    data["image"].update(width=40000, height=8)
    (tmp_path / "wide.json").write_text(json.dumps(data))
    code = shadowvol_main(["render", str(tmp_path / "huge.json"), str(tmp_path / "wide.json"),
                     "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert "huge.json: image: 100000x100000 is more than 268435456 pixels" in err
    assert "wide.json: image: 40000x8 is larger than this GL allows" in err


@pytest.mark.parametrize("command", ["compare", "planar", "shadowmap"])
def test_every_command_names_the_scene_of_an_image_too_wide(tmp_path, capsys, command):
    """The GL's size limit is the Renderer's check now, for every command that renders: the
    line names the scene file, the key and the limit, exit 2, nothing written."""
    data = json.loads((lambda p: (save_scene(small_scene(), p), p.read_text())[1])(
        tmp_path / "s.json"))
    data["image"].update(width=40000, height=8)
    (tmp_path / "wide.json").write_text(json.dumps(data))
    out = tmp_path / "out.png"
    assert shadowvol_main([command, str(tmp_path / "wide.json"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path / 'wide.json'}: image: 40000x8 is larger than this "
                          "GL allows (") and err.count("\n") == 1, err
    assert not out.exists()


# ---- atomic outputs ----------------------------------------------------------------------------

@pytest.mark.parametrize("interrupt", [RuntimeError("disk on fire"), KeyboardInterrupt()])
def test_an_interrupted_write_leaves_nothing(tmp_path, interrupt):
    target = tmp_path / "out.png"
    with pytest.raises(type(interrupt)):
        with atomic_write(target) as f:
            f.write(b"half a PNG")
            raise interrupt
    assert not target.exists() and leftovers(tmp_path) == []
    # an existing file stays as it was
    target.write_bytes(b"old")
    with pytest.raises(type(interrupt)):
        with atomic_write(target) as f:
            f.write(b"new, half")
            raise interrupt
    assert target.read_bytes() == b"old" and leftovers(tmp_path) == []


def test_writers_go_through_atomic_write(tmp_path, monkeypatch):
    """Ctrl-C inside the PNG / npz encoder: nothing written (the encoders run before the file
    is opened, and the write itself is atomic)."""
    import PIL.Image

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(PIL.Image.Image, "save", interrupted)
    with pytest.raises(KeyboardInterrupt):
        save_png(tmp_path / "a.png", np.zeros((4, 4, 3), np.uint8))
    monkeypatch.setattr(np.lib.format, "write_array", interrupted)  # io.npz_bytes' encoder
    with pytest.raises(KeyboardInterrupt):
        save_masks(tmp_path / "m.npz", np.zeros((1, 4, 4), bool), np.zeros((4, 4), bool))
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_during_a_render_command_leaves_no_file(tmp_path, monkeypatch, capsys):
    import shadowvol.io

    real = shadowvol.io.atomic_write
    calls = []

    def interrupt_second(path, *args):  # the image is written, Ctrl-C while writing the masks
        calls.append(path)
        if len(calls) == 2:
            def gen():
                with real(path) as f:
                    f.write(b"partial")
                    raise KeyboardInterrupt
                    yield f  # pragma: no cover
            import contextlib
            return contextlib.contextmanager(gen)()
        return real(path, *args)

    save_scene(small_scene(), tmp_path / "s.json")
    monkeypatch.setattr(shadowvol.io, "atomic_write", interrupt_second)
    out = tmp_path / "out"
    code = shadowvol_main(["render", str(tmp_path / "s.json"), "-o", str(out / "img.png"),
                           "--masks", str(out / "m.npz")])
    assert code == 130 and capsys.readouterr().err.strip() == "error: interrupted"
    assert sorted(os.listdir(out)) == ["img.png"]  # complete; the masks never appeared
