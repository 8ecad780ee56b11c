"""The shader loader: files found by name (source checkout and installed wheel), #defines that
keep line numbers, errors naming file and line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from builders import ROOT

from shadowvol.raster import glsl

SHADERS = sorted((ROOT / "shaders").glob("*.*"))


def test_every_shader_is_a_real_glsl_450_file():
    assert {p.suffix for p in SHADERS} <= {".vert", ".geom", ".frag"}
    assert len(SHADERS) >= 8
    for path in SHADERS:
        assert path.read_text().startswith("#version 450 core\n"), path.name


def test_shared_tri_sign_is_identical_in_both_shaders():
    """tri_sign must be the same text wherever it is used, or sides and caps could disagree."""
    def block(name):
        text = (ROOT / "shaders" / name).read_text()
        start = text.index("// --- tri_sign")
        return text[start:text.index("// ----", start + 10)]

    assert block("silhouette.geom") == block("caps.vert")


BAD = """#version 450 core
// a comment
out vec4 f_colour;
void main() {
    f_colour = vec4(undeclared_name, 1.0);
}
"""


@pytest.mark.parametrize("defines", [None, {"FIRST": 1, "SECOND": "vec3(1.0)"}])
def test_compile_error_names_file_and_line(ctx, tmp_path, monkeypatch, defines):
    (tmp_path / "bad.frag").write_text(BAD)
    monkeypatch.setattr(glsl, "SHADER_DIRS", (tmp_path,) + glsl.SHADER_DIRS)
    with pytest.raises(glsl.ShaderError) as err:
        glsl.program(ctx, "volume_side.vert", "bad.frag", defines=defines)
    assert f"{tmp_path / 'bad.frag'}:5:" in str(err.value)
    assert "undeclared_name" in str(err.value)


def test_defines_go_after_version_with_a_line_directive():
    text = glsl.shader_source("caps.vert", {"FAR_CAP": 1})
    lines = text.splitlines()
    assert lines[0] == "#version 450 core"
    assert lines[1] == "#define FAR_CAP 1" and lines[2] == "#line 2"
    assert "\n".join(lines[3:]) + "\n" == \
        (ROOT / "shaders" / "caps.vert").read_text().split("\n", 1)[1]


def test_missing_shader_and_bad_define(ctx):
    with pytest.raises(glsl.ShaderError, match="not found"):
        glsl.shader_path("nope.vert")
    with pytest.raises(glsl.ShaderError, match="bad #define"):
        glsl.shader_source("scene.vert", {"not a name": 1})


def test_every_program_links(ctx):
    pairs = [("scene.vert", "ambient.frag", None), ("scene.vert", "phong.frag", None),
             ("scene.vert", "volume.frag", None), ("volume_side.vert", "volume.frag", None),
             ("far_cap.vert", "volume.frag", None), ("caps.vert", "volume.frag", None),
             ("edge.vert", "volume.frag", "silhouette.geom"),
             ("shadowmap.vert", "shadowmap.frag", None)]
    for vert, frag, geom in pairs:
        glsl.program(ctx, vert, frag, geom).release()


def test_source_checkout_finds_top_level_shaders(tmp_path):
    """Run from the checkout itself (not an installed copy): <repo>/shaders beside the package."""
    probe = "from shadowvol.raster import glsl; print(glsl.shader_path('scene.vert'))"
    run = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True,
                         text=True, env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=120)
    assert run.returncode == 0, run.stderr
    assert Path(run.stdout.strip()) == ROOT / "shaders" / "scene.vert"
