"""The hostile-input sweep over what was added since the first one: area lights' sizes and sample
counts in both commands, --outputs, EXR and 16-bit PNG, path tracing's, radiosity's and the
batch's options, the memory budget, the demo's size and the ray tree's pixel.  Each is bad input:
exit 2, one `error:` line naming the flag or the file and key, no traceback, nothing written.
In-process (each command's `main`), so the sweep costs seconds, not a process per case."""

from __future__ import annotations

import json
import tomllib

import pytest
from builders import SCENES

from shadowvol.cli import status
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.cli.raytrace import main as raytrace_main

pytestmark = pytest.mark.gl

SOFT = tomllib.loads((SCENES / "soft.toml").read_text())
CAGE = str(SCENES / "cage.toml")
CORNELL = str(SCENES / "cornell.toml")

AREA_VALUES = [
    ("size", [0, 1], "must be positive"), ("size", [-1, 1], "must be positive"),
    ("size", [float("nan"), 1], "non-finite"), ("size", [1e40, 1], "float32 range"),
    ("samples", 0, "1..65535"), ("samples", -1, "1..65535"), ("samples", 2**31, "1..65535"),
    ("samples", 10**7, "1..65535"), ("samples", 1.5, "whole number"),
    ("samples", "16", "whole number"), ("samples", True, "whole number"),
    ("radius", 0, "unknown key"),
]


def _soft_with(tmp_path, key, value) -> tuple[str, str]:
    scene = json.loads(json.dumps(SOFT))
    light = next(i for i, light in enumerate(scene["lights"]) if light["type"] == "rect")
    scene["lights"][light][key] = value
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return str(path), f"lights[{light}].{key}"


def _refused(code: int, err: str, *words: str) -> None:
    lines = [line for line in err.strip().splitlines() if line.strip()]
    assert code == status.BAD_INPUT, err
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    for word in words:
        assert word in lines[0], lines[0]


def _written(tmp_path) -> set[str]:
    return {p.name for p in tmp_path.iterdir()} - {"scene.json"}


@pytest.mark.parametrize("key, value, words", AREA_VALUES,
                         ids=[f"{k}={v!r}" for k, v, _ in AREA_VALUES])
@pytest.mark.parametrize("command", ["render", "raytrace masks"])
def test_an_area_light_out_of_range(tmp_path, capsys, command, key, value, words):
    scene, where = _soft_with(tmp_path, key, value)
    code = (shadowvol_main(["render", scene, "-o", str(tmp_path / "o.png")])
            if command == "render" else
            raytrace_main(["masks", scene, "-o", str(tmp_path / "o.npz")]))
    _refused(code, capsys.readouterr().err, "scene.json", where, words)
    assert _written(tmp_path) == set()


OPTIONS = [
    ("render --outputs bogus", ["render", CAGE, "-o", "o.png", "--masks", "m.npz", "--outputs",
                                "depth,bogus"], ("--outputs", "bogus")),
    ("render --outputs ,", ["render", CAGE, "-o", "o.png", "--outputs", ","], ("--outputs",)),
    ("render --exr .png", ["render", CAGE, "-o", "o.png", "--exr", "x.png"], ("--exr", ".exr")),
    ("render --png16 = -o", ["render", CAGE, "-o", "o.png", "--png16", "o.png"],
     ("--png16", "-o")),
    ("render --memory-budget 1e999", ["render", CAGE, "-o", "o.png", "--memory-budget", "1e999"],
     ("--memory-budget", "1e999")),
    ("batch --workers 0", ["batch", str(SCENES / "turntable.jsonl"), "-o", "b", "--workers", "0"],
     ("--workers",)),
    ("batch --shard 3/2", ["batch", str(SCENES / "turntable.jsonl"), "-o", "b", "--shard", "3/2"],
     ("--shard", "3/2")),
    ("demo --size 0x0", ["demo", "-o", "d", "--size", "0x0"], ("--size", "0x0")),
]

RAYTRACE_OPTIONS = [
    ("path --spp 0", ["render", CORNELL, "-o", "o.png", "--integrator", "path", "--spp", "0"],
     ("--spp", ">= 1")),
    ("path --spp -1", ["render", CORNELL, "-o", "o.png", "--integrator", "path", "--spp", "-1"],
     ("--spp",)),
    ("path --spp 2**62", ["render", CORNELL, "-o", "o.png", "--integrator", "path", "--spp",
                          str(2**62)], ("cornell.toml", "image", "memory budget")),
    ("whitted --spp 0", ["render", CAGE, "-o", "o.png", "--spp", "0"], ("--spp",)),
    ("radiosity --level -1", ["radiosity", CORNELL, "-o", "o.png", "--level", "-1"],
     ("--level",)),
    ("radiosity --level 40", ["radiosity", CORNELL, "-o", "o.png", "--level", "40"],
     ("--level", "4^40")),
    ("radiosity --rays 0", ["radiosity", CORNELL, "-o", "o.png", "--rays", "0"], ("--rays",)),
    ("radiosity --tol -1", ["radiosity", CORNELL, "-o", "o.png", "--tol", "-1"], ("--tol",)),
    ("radiosity --tol nan", ["radiosity", CORNELL, "-o", "o.png", "--tol", "nan"], ("--tol",)),
    ("radiosity --shots 0", ["radiosity", CORNELL, "-o", "o.png", "--shots", "0"], ("--shots",)),
    ("radiosity --seed -1", ["radiosity", CORNELL, "-o", "o.png", "--seed", "-1"],
     ("--seed: must be >= 0",)),
    ("radiosity --rays 10**23", ["radiosity", CORNELL, "-o", "o.png", "--rays", str(10**23)],
     ("--rays: must be < 2^31",)),
    ("render --max-depth -1", ["render", CAGE, "-o", "o.png", "--max-depth", "-1"],
     ("--max-depth",)),
    ("tree --pixel 2**63", ["tree", CAGE, "--pixel", str(2**63), "0"], ("--pixel", "outside")),
]


@pytest.mark.parametrize("argv, words", [c[1:] for c in OPTIONS], ids=[c[0] for c in OPTIONS])
def test_a_shadowvol_option_out_of_range(tmp_path, capsys, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    _refused(shadowvol_main(argv), capsys.readouterr().err, *words)
    assert _written(tmp_path) == set()


@pytest.mark.parametrize("argv, words", [c[1:] for c in RAYTRACE_OPTIONS],
                         ids=[c[0] for c in RAYTRACE_OPTIONS])
def test_a_raytrace_option_out_of_range(tmp_path, capsys, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    _refused(raytrace_main(argv), capsys.readouterr().err, *words)
    assert _written(tmp_path) == set()
