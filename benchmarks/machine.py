"""The machine a run measures on, and the run's log and memory clock."""

from __future__ import annotations

import os
import platform
import resource
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def log(*args) -> None:
    print(time.strftime("%H:%M:%S"), *args, file=sys.stderr, flush=True)


def maxrss_mb() -> float:
    """Peak resident set size of this process so far (Linux reports KiB), in MB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def machine(ctx) -> dict:
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for pkg in ("numpy", "moderngl", "glcontext", "embreex", "pyrender", "PyOpenGL", "trimesh",
                "matplotlib", "mitsuba", "numba"):
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "not installed"
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--",
                                "shadowvol", "raytrace", "shaders", "benchmarks"],
                               capture_output=True, text=True).stdout
    except OSError:
        commit, dirty = "?", ""
    dirty = [line for line in dirty.splitlines() if line.strip()]
    return {
        "cpu": cpu, "cores": os.cpu_count(), "usable_cores": len(os.sched_getaffinity(0)),
        "gl_renderer": ctx.info["GL_RENDERER"], "gl_version": ctx.info["GL_VERSION"],
        "gl_vendor": ctx.info["GL_VENDOR"], "python": platform.python_version(),
        "os": platform.platform(), "versions": versions,
        "commit": commit + (f" plus uncommitted changes to {', '.join(l[3:] for l in dirty)}"
                            if dirty else ""),
        "date": time.strftime("%Y-%m-%d %H:%M %Z"), "load_start": os.getloadavg(),
    }
