"""The shader loader: finds GLSL files by name and links them into moderngl programs.

Shaders live as real files in the top-level `shaders/` folder of a source checkout; an installed
wheel carries the same files as the package `shadowvol.shaders` (pyproject maps one onto the
other).  The loader may insert `#define` lines right after `#version`, followed by a `#line`
directive so that the compiler's line numbers stay those of the file; it never edits shader text
otherwise.  Compile and link errors raise `ShaderError` naming the file and the line.
"""

from __future__ import annotations

import re
from pathlib import Path

import moderngl

from shadowvol.errors import RenderError
from shadowvol.resources import data_dirs

SHADER_DIRS = data_dirs("shaders")  # the installed wheel's, then a source checkout's
_STAGES = {"vertex_shader": "vertex", "geometry_shader": "geometry", "fragment_shader": "fragment"}
# Line references in driver logs: Mesa "0:12(5): error", NVIDIA "0(12) : error", AMD "ERROR: 0:12:"
_LINE = re.compile(r"\b\d+[:(](\d+)\)?")
_DEFINE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class ShaderError(RenderError):
    """A shader that is missing, fails to compile, or fails to link."""


def shader_path(name: str) -> Path:
    """The file of shader `name` (e.g. "scene.vert"), from the first folder that has it."""
    for folder in SHADER_DIRS:
        path = folder / name
        if path.is_file():
            return path
    raise ShaderError(f"shader {name!r} not found in " + " or ".join(str(d) for d in SHADER_DIRS))


def shader_source(name: str, defines: dict[str, object] | None = None) -> str:
    """The text of shader `name`, with `#define NAME VALUE` lines inserted after `#version`."""
    path = shader_path(name)
    text = path.read_text(encoding="utf-8")
    first, sep, rest = text.partition("\n")
    if not first.startswith("#version"):
        raise ShaderError(f"{path}:1: the first line must be #version")
    if not defines:
        return text
    lines = []
    for key, value in defines.items():
        if not _DEFINE_NAME.fullmatch(key):
            raise ShaderError(f"bad #define name {key!r} for {name}")
        lines.append(f"#define {key} {value}")
    # `#line 2` makes the line after it line 2 again, as in the file.
    return first + "\n" + "\n".join(lines) + "\n#line 2\n" + rest


def program(ctx: moderngl.Context, vertex: str, fragment: str | None = None,
            geometry: str | None = None, defines: dict[str, object] | None = None,
            varyings: tuple[str, ...] = ()) -> moderngl.Program:
    """Compile and link a program from shader files named by `vertex`, `geometry`, `fragment`."""
    names = {"vertex": vertex, "geometry": geometry, "fragment": fragment}
    sources = {stage: shader_source(n, defines) for stage, n in names.items() if n}
    try:
        return ctx.program(vertex_shader=sources["vertex"],
                           geometry_shader=sources.get("geometry"),
                           fragment_shader=sources.get("fragment"), varyings=varyings)
    except moderngl.Error as exc:
        raise ShaderError(_explain(str(exc), names)) from None


def _explain(log: str, names: dict[str, str | None]) -> str:
    """Turn moderngl's compiler/linker log into 'file:line: message' lines."""
    stage = None
    for key, value in _STAGES.items():
        if key in log:
            stage = value
    if stage is None or not names.get(stage):
        files = ", ".join(n for n in names.values() if n)
        return f"linking {files} failed:\n{log.strip()}"
    path = shader_path(names[stage])
    out = []
    for line in log.splitlines():
        m = _LINE.search(line)
        if m and ("error" in line.lower() or "warning" in line.lower()):
            out.append(f"{path}:{m.group(1)}: {line.strip()}")
    return "\n".join(out) if out else f"{path}: compile failed:\n{log.strip()}"


def set_uniform(program: moderngl.Program, name: str, value) -> None:
    """Set a uniform if the program uses it (the linker drops unused ones)."""
    if name in program:
        member = program[name]
        if isinstance(value, bytes):
            member.write(value)
        else:
            member.value = value
