"""The product as a user installs it: the package built from a copy of the checkout's files,
installed with pip into a fresh venv outside the checkout, and run from there.

Every other test imports the checkout (`pythonpath = ["."]`), so a module left out of the wheel,
a shader or scene not shipped, or a dependency missing from `pyproject.toml` would pass them all;
once, the batch's dataset package (`shadowvol.batch.datasets`) was missing from the wheel and
every command failed to import.
Here the README's first command runs verbatim in that venv (it builds and installs the wheel),
then, from a folder that is not the checkout, `shadowvol batch` in every `--format`, `raytrace
masks`, `shadowvol masks`, `shadowvol demo --small` and a script importing every public module.  The venv has the
runtime dependencies only (no test extra), resolved by pip from the package index as a user's
would be.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import textwrap
from pathlib import Path

import numpy as np
import pytest
from builders import ROOT
from PIL import Image

pytestmark = pytest.mark.gl  # the installed commands render

PIP_TIMEOUT = 900
RUN_TIMEOUT = 300


def readme_first_command() -> str:
    return re.findall(r"```bash\n(.*?)\n```", (ROOT / "README.md").read_text(), flags=re.S)[0]


def checkout_files() -> list[str]:
    """The files a fresh clone has (tracked, plus new files git does not ignore, so that work
    not yet committed is tested too); a folder that is not a git repository is copied whole but
    for build leftovers."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                             cwd=ROOT, capture_output=True, check=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError):
        skip = {".git", "__pycache__", "build", "dist", ".pytest_cache", ".hypothesis", "out"}
        return [str(p.relative_to(ROOT)) for p in ROOT.rglob("*")
                if p.is_file() and not skip & set(p.relative_to(ROOT).parts)
                and not any(part.endswith(".egg-info") for part in p.parts)]
    return [name for name in out.decode().split("\0") if name and (ROOT / name).is_file()]


class Installed:
    """A fresh venv with the package installed by the README's first command."""

    def __init__(self, base: Path):
        self.base = base
        self.src = base / "src"
        self.venv = base / "venv"
        self.work = base / "work"
        self.bin = self.venv / "bin"
        self.env = {k: v for k, v in os.environ.items()
                    if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME", "PYTHONSTARTUP")}
        self.env["PATH"] = f"{self.bin}{os.pathsep}{os.environ.get('PATH', '')}"
        self.env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"

    def run(self, command: str | list[str], cwd: Path | None = None,
            timeout: int = RUN_TIMEOUT) -> subprocess.CompletedProcess:
        shell = isinstance(command, str)
        return subprocess.run(["bash", "-c", command] if shell else command,
                              cwd=cwd or self.work, env=self.env, capture_output=True,
                              text=True, timeout=timeout)

    def python(self, code: str, timeout: int = RUN_TIMEOUT) -> subprocess.CompletedProcess:
        return self.run([str(self.bin / "python"), "-c", textwrap.dedent(code)], timeout=timeout)

    def site_packages(self) -> Path:
        done = self.python("import sysconfig; print(sysconfig.get_paths()['purelib'])")
        assert done.returncode == 0, done.stderr
        return Path(done.stdout.strip())


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Installed:
    inst = Installed(tmp_path_factory.mktemp("installed"))
    for name in checkout_files():
        target = inst.src / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, target)
    inst.work.mkdir()
    made = subprocess.run([sys.executable, "-m", "venv", str(inst.venv)], capture_output=True,
                          text=True, timeout=PIP_TIMEOUT)
    assert made.returncode == 0, made.stderr
    # the README's first command, verbatim, in the fresh copy (the user's clone)
    done = inst.run(readme_first_command(), cwd=inst.src, timeout=PIP_TIMEOUT)
    inst.readme = done
    return inst


def test_readme_first_command_works_in_a_fresh_venv(installed):
    done = installed.readme
    assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-4000:])
    out = installed.src / "out"
    image = np.asarray(Image.open(out / "cage.png"))
    assert image.ndim == 3 and image.shape[2] == 3 and image.std() > 0, "a blank image"
    with np.load(out / "cage_masks.npz") as masks:
        lit, coverage = masks["lit"], masks["coverage"]
        assert lit.dtype == bool and lit.shape[1:] == coverage.shape == image.shape[:2]
        assert lit[:, coverage].any() and not lit[:, coverage].all(), "no shadow in the cage"
        assert {"K", "camera_to_world"} <= set(masks.files)
    assert Image.open(out / "cage_volumes.png").size[0] > 0


def test_the_installed_package_is_the_one_imported(installed):
    site = installed.site_packages()
    done = installed.python("""
        import shadowvol, raytrace, shutil
        print(shadowvol.__file__); print(raytrace.__file__); print(shutil.which("shadowvol"))
        """)
    assert done.returncode == 0, done.stderr
    shadowvol_file, raytrace_file, script = done.stdout.split()
    assert Path(shadowvol_file).is_relative_to(site), shadowvol_file
    assert Path(raytrace_file).is_relative_to(site), raytrace_file
    assert Path(script).is_relative_to(installed.bin), script


def test_the_wheel_ships_every_module_shader_and_scene(installed):
    """Every Python module of shadowvol/ and raytrace/ in the checkout, every shader and every
    example scene is in the installed package: a package found by setuptools, not listed."""
    site = installed.site_packages()
    src = installed.src
    expected = {str(p.relative_to(src)) for top in ("shadowvol", "raytrace")
                for p in (src / top).rglob("*.py")}
    expected |= {f"shadowvol/shaders/{p.name}" for p in (src / "shaders").iterdir()
                 if p.suffix in (".vert", ".geom", ".frag")}
    expected |= {f"shadowvol/scenes/{p.relative_to(src / 'scenes')}"
                 for p in (src / "scenes").rglob("*")
                 if p.suffix in (".toml", ".json", ".jsonl", ".obj") or p.name == "README.md"}
    assert len(expected) > 150
    missing = sorted(name for name in expected if not (site / name).is_file())
    assert not missing, f"not in the installed package: {missing}"


def test_the_installed_package_loads_its_own_shaders_and_scenes(installed):
    """shadowvol.shaders and shadowvol.scenes (the top-level shaders/ and scenes/ mapped into the
    package) are found inside the installed package, not in a checkout."""
    site = installed.site_packages()
    done = installed.python("""
        import shadowvol
        from shadowvol.raster import glsl
        assert glsl.shader_source("scene.vert").startswith("#version")
        print(glsl.shader_path("scene.vert")); print(shadowvol.example_scene("cage"))
        """)
    assert done.returncode == 0, done.stderr
    shader, scene = map(Path, done.stdout.split())
    assert shader == site / "shadowvol" / "shaders" / "scene.vert"
    assert scene == site / "shadowvol" / "scenes" / "cage.toml"


def test_every_public_module_imports(installed):
    """Each public module imports with the runtime dependencies alone, except where the one
    package it lacks is an optional extra's (the `fast` extra's numba, say)."""
    done = installed.python("""
        import importlib, importlib.metadata as md, json, pkgutil, re
        import shadowvol, raytrace
        core = {re.split(r"[ ;<>=!\\[]", r)[0].lower() for r in md.requires("shadowvol")
                if "extra ==" not in r}
        extra = {re.split(r"[ ;<>=!\\[]", r)[0].lower() for r in md.requires("shadowvol")
                 if "extra ==" in r} - core
        names, failed = [], []
        for pkg in (shadowvol, raytrace):
            for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
                if any(part.startswith("_") for part in info.name.split(".")):
                    continue
                names.append(info.name)
                try:
                    importlib.import_module(info.name)
                except ModuleNotFoundError as e:
                    if (e.name or "").split(".")[0].lower() not in extra:
                        failed.append(f"{info.name}: {e!r}")
                except Exception as e:
                    failed.append(f"{info.name}: {e!r}")
        print(json.dumps({"names": names, "failed": failed}))
        """)
    assert done.returncode == 0, done.stderr[-4000:]
    result = json.loads(done.stdout.splitlines()[-1])
    assert len(result["names"]) > 100
    assert "shadowvol.batch.datasets" in result["names"]
    assert not result["failed"], result["failed"]


def batch_formats(installed) -> list[str]:
    done = installed.run("shadowvol batch --help")
    assert done.returncode == 0, done.stderr
    choices = re.search(r"--format \{([^}]*)\}", done.stdout)
    assert choices, done.stdout
    return choices.group(1).split(",")


def example_scene(installed, name: str) -> str:
    done = installed.python(f"import shadowvol; print(shadowvol.example_scene({name!r}))")
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_batch_in_every_format(installed):
    formats = batch_formats(installed)
    assert {"files", "webdataset", "nerfstudio", "bop", "coco", "istd", "soba"} <= set(formats)
    job = {"name": "cage", "scene": example_scene(installed, "cage"), "size": [40, 30],
           "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.5,
                                 "elevation": 28.0, "start": 10.0, "sweep": 80.0,
                                 "frames": 2}},
           "outputs": ["image", "masks"], "seed": 0}
    (installed.work / "jobs.jsonl").write_text(json.dumps(job) + "\n")
    for fmt in formats:
        out = installed.work / f"ds-{fmt}"
        done = installed.run(["shadowvol", "batch", "jobs.jsonl", "-o", str(out),
                              "--format", fmt])
        assert done.returncode == 0, (fmt, done.stderr[-3000:])
        records = [json.loads(line) for line in (out / "manifest.jsonl").read_text().splitlines()]
        frames = [r for r in records if "files" in r]
        assert len(frames) == 2 and not any(r.get("error") for r in records), (fmt, records)
        for record in frames:  # every file the manifest names is there, with its bytes
            for entry in record["files"].values():
                if "tar" in entry:
                    with tarfile.open(out / entry["tar"]) as tar:
                        data = tar.extractfile(entry["member"]).read()
                else:
                    data = (out / entry["path"]).read_bytes()
                assert hashlib.sha256(data).hexdigest() == entry["sha256"], (fmt, entry)
        index = {"nerfstudio": "cage/transforms.json", "coco": "annotations.json",
                 "bop": "train/000000/scene_gt.json", "istd": "cage/istd.json",
                 "soba": "cage/annotations.json",
                 "soba-lights": "cage/annotations.json"}.get(fmt)
        if index:
            assert json.loads((out / index).read_text()), (fmt, index)
        if fmt == "webdataset":
            shards = sorted(out.glob("*.tar"))
            assert shards and len({m.name.split(".")[0] for s in shards
                                   for m in tarfile.open(s).getmembers()}) == 2


def test_raytrace_masks(installed):
    done = installed.run(["raytrace", "masks", example_scene(installed, "cage"), "-o", "m.npz",
                          "--outputs", "depth,object_id"])
    assert done.returncode == 0, done.stderr[-3000:]
    with np.load(installed.work / "m.npz") as masks:
        lit, coverage, depth = masks["lit"], masks["coverage"], masks["depth"]
        assert lit.shape[1:] == coverage.shape == depth.shape and coverage.any()
        assert lit[:, coverage].any() and not lit[:, coverage].all()
    assert (installed.work / "m.png").is_file()


def test_shadowvol_masks_says_which_renderer_made_them(installed):
    """The masks alone through the installed command (numba, the `fast` extra, is not in this
    venv: the ray tracer's single rays are what auto weighs), the renderer in the log line; the
    two renderers named give the same file but at tie pixels."""
    scene = example_scene(installed, "cage")
    for renderer in ("auto", "shadowvol", "raytrace"):
        done = installed.run(["shadowvol", "masks", scene, "-o", f"{renderer}.npz",
                              "--renderer", renderer])
        assert done.returncode == 0, done.stderr[-3000:]
        line = done.stderr.strip().splitlines()[-1]
        assert line.startswith(f"wrote {renderer}.npz by the "), line
        assert f"({renderer}: " in line and (renderer != "auto" or "single rays" in line), line
    with np.load(installed.work / "shadowvol.npz") as a, \
            np.load(installed.work / "raytrace.npz") as b:
        assert a.files == b.files and a["coverage"].any()
        assert (a["lit"] != b["lit"]).mean() < 1e-4


def test_demo_small(installed):
    done = installed.run(["shadowvol", "demo", "--small", "-o", "demo"], timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    demo = installed.work / "demo"
    slides = sorted(demo.glob("*.png"))
    assert len(slides) >= 10 and (demo / "index.html").is_file()
    for slide in slides:
        assert Image.open(slide).size == (480, 270), slide.name
