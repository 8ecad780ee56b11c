"""Where the project's data folders are.

`shaders/` and `scenes/` live at the top of a source checkout, beside `shadowvol/`; an installed
wheel carries the same files as the packages `shadowvol.shaders` and `shadowvol.scenes`
(pyproject maps one onto the other), so a plain `pip install .` has them too.
"""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def data_dirs(name: str) -> tuple[Path, Path]:
    """The folders that may hold `name` ("shaders" or "scenes"): the installed package's
    first (<site-packages>/shadowvol/NAME), then the source checkout's (<repo>/NAME)."""
    return (_HERE / name, _HERE.parent / name)


def data_dir(name: str) -> Path:
    """The first folder of `data_dirs(name)` that exists, else the source checkout's (whose
    absence the caller reports)."""
    installed, checkout = data_dirs(name)
    return installed if installed.is_dir() else checkout


def example_scene(name: str) -> Path:
    """The path of an example scene shipped with shadowvol: `example_scene("cage")` is the
    installed (or checkout's) scenes/cage.toml.  Raises SceneError naming the examples there
    are when `name` is not one of them."""
    from shadowvol.scene import (
        SceneError,  # numpy: not on `import shadowvol` (see __init__)
    )


    folder = data_dir("scenes")
    stem = Path(name).stem if Path(name).suffix in (".toml", ".json") else name
    for suffix in (".toml", ".json"):
        path = folder / f"{stem}{suffix}"
        if path.is_file():
            return path
    known = sorted(p.stem for p in folder.glob("*.toml")) if folder.is_dir() else []
    raise SceneError("example_scene", f"no example scene {name!r}; the examples are "
                                      f"{', '.join(known) or '(none: scenes folder missing)'}")
