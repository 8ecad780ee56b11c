"""Stress (not a test): SIGINT and SIGTERM at random moments to batch, render and raytrace runs,
each under faulthandler, looking for a crash in native code (issue "As shipped, nothing lost":
a SIGSEGV was seen once after a SIGINT to a coco batch, and once after a SIGTERM before; its
cause and a reproducer that hits it in a few signals: `benchmarks/signal_in_compile.py`).

    python -m benchmarks.stress_signals [--runs 1000] [--seed 0] [--json out.json]

Each run starts one command in a fresh output folder (small frames, so that a run lasts about
as long as its start-up), waits a random time drawn over the command's own measured duration,
sends SIGINT or SIGTERM, and classifies how it ended:

* `ok`: 0 (finished before the signal), 130 or 143 (the documented statuses), or -2 / -15 (the
  signal came after the command had returned: `shadowvol.signals.finished` restores the default
  handlers, so the process is killed the default way);
* `crash`: killed by a signal we did not send (-11 SIGSEGV, -6 SIGABRT, ...) or hung, whenever
  the signal came; kept with the faulthandler dump of every thread (PYTHONFAULTHANDLER=1), the
  command, the signal and the delay;
* `early`: the signal came before the entry point had installed its handlers (read from
  /proc/PID/status just before sending): Python's own start-up answers it, no code of ours;
* `bad status` / `traceback`: after the handlers, another status, or a Python traceback.

The summary prints the counts per command and per outcome, and the first lines of each crash.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

OK = {0, 130, 143, -signal.SIGINT, -signal.SIGTERM}
HUNG = 999
ENTRIES = {"shadowvol": "from shadowvol.cli import shadowvol_entry as e; import sys; "
                        "sys.exit(e(sys.argv[1:]))",
           "raytrace": "from shadowvol.cli import raytrace_entry as e; import sys; "
                       "sys.exit(e(sys.argv[1:]))"}


def make_inputs(folder: Path) -> dict[str, list[str]]:
    """A small copy of the cage example and a job file of it; the commands to stress."""
    import shadowvol

    scene = shadowvol.load_scene(shadowvol.example_scene("cage")).replace(width=96, height=72)
    shadowvol.save_scene(scene, folder / "cage.toml")
    job = {"name": "cage", "scene": str(folder / "cage.toml"), "size": [64, 48],
           "cameras": {"orbit": {"center": [-0.6, 1.0, -0.8], "radius": 7.5, "elevation": 28.0,
                                 "start": 10.0, "sweep": 80.0, "frames": 6}},
           "jitter": {"eye": 0.2, "lights": 0.2}, "outputs": ["image", "masks"], "seed": 0}
    (folder / "jobs.jsonl").write_text(json.dumps(job) + "\n")
    scene_file, jobs = str(folder / "cage.toml"), str(folder / "jobs.jsonl")
    return {
        "batch coco": ["shadowvol", "batch", jobs, "-o", "{out}", "--format", "coco"],
        "batch files": ["shadowvol", "batch", jobs, "-o", "{out}"],
        "batch bop": ["shadowvol", "batch", jobs, "-o", "{out}", "--format", "bop"],
        "batch nerfstudio": ["shadowvol", "batch", jobs, "-o", "{out}", "--format", "nerfstudio"],
        "batch webdataset": ["shadowvol", "batch", jobs, "-o", "{out}", "--format", "webdataset"],
        "batch 2 workers": ["shadowvol", "batch", jobs, "-o", "{out}", "--workers", "2"],
        "render": ["shadowvol", "render", scene_file, "-o", "{out}/x.png", "--masks",
                   "{out}/x.npz", "--outputs", "all"],
        "raytrace masks": ["raytrace", "masks", scene_file, "-o", "{out}/m.npz"],
        "raytrace render": ["raytrace", "render", scene_file, "-o", "{out}/r.png"],
    }


def launch(argv: list[str], out: Path) -> subprocess.Popen:
    tool, *rest = argv
    env = dict(os.environ, PYTHONFAULTHANDLER="1")
    return subprocess.Popen([sys.executable, "-c", ENTRIES[tool],
                             *[a.replace("{out}", str(out)) for a in rest]],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)


def duration(argv: list[str], scratch: Path) -> float:
    """One undisturbed run's wall time (the window the signals are drawn over)."""
    out = Path(tempfile.mkdtemp(dir=scratch))
    start = time.perf_counter()
    proc = launch(argv, out)
    _, err = proc.communicate(timeout=600)
    if proc.returncode != 0:
        raise SystemExit(f"stress_signals: {argv[:2]} failed undisturbed: {err[-500:]}")
    shutil.rmtree(out)
    return time.perf_counter() - start


def catches_signals(pid: int) -> bool:
    """Whether the process has installed its own SIGTERM handler yet (the entry point's first
    act; Python itself does not catch SIGTERM), read from /proc/PID/status."""
    try:
        with open(f"/proc/{pid}/status") as f:
            caught = next(int(line.split()[1], 16) for line in f if line.startswith("SigCgt"))
    except (OSError, StopIteration):
        return False
    return bool(caught & (1 << (signal.SIGTERM - 1)))


def outcome(code: int, err: str, handlers: bool) -> str:
    """`crash`: killed by a signal we did not send (SIGSEGV, SIGABRT, ...) or hung, at any time;
    `early`: the signal came while Python was still starting, before the entry point installed
    its handlers (Python's own KeyboardInterrupt traceback, or 'init_import_site' failing: no
    code of ours has run); `bad status` / `traceback`: after the handlers, a status other than
    the documented ones, or a traceback."""
    if code < 0 and code not in OK or code == HUNG:
        return "crash"
    bad = code not in OK or "Traceback (most recent call last)" in err
    if bad and not handlers:
        return "early"
    if code not in OK:
        return "bad status"
    return "traceback" if bad else "ok"


def stress(runs: int, seed: int, scratch: Path) -> dict:
    rng = random.Random(seed)
    commands = make_inputs(scratch)
    windows = {name: duration(argv, scratch) for name, argv in commands.items()}
    counts: dict[str, Counter] = {name: Counter() for name in commands}
    statuses: dict[str, Counter] = {name: Counter() for name in commands}  # 0: done first
    crashes = []
    names = sorted(commands)
    for i in range(runs):
        name = names[i % len(names)]
        signum = rng.choice((signal.SIGINT, signal.SIGTERM))
        delay = rng.uniform(0.0, windows[name] * 1.1)
        out = Path(tempfile.mkdtemp(dir=scratch))
        proc = launch(commands[name], out)
        time.sleep(delay)
        handlers = catches_signals(proc.pid)
        if proc.poll() is None:
            proc.send_signal(signum)
        try:
            _, err = proc.communicate(timeout=300)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, err = proc.communicate()
            err = "HUNG 300 s after the signal\n" + err
            proc.returncode = HUNG
        kind = outcome(proc.returncode, err, handlers)
        counts[name][kind] += 1
        statuses[name][proc.returncode] += 1
        if kind != "ok" and kind != "early":
            crashes.append({"command": name, "signal": signal.Signals(signum).name,
                            "delay_s": round(delay, 4), "status": proc.returncode,
                            "kind": kind, "stderr": err[-6000:]})
            head = " | ".join(err.strip().splitlines()[-3:])
            print(f"stress_signals: {kind}: {name} {signal.Signals(signum).name} after "
                  f"{delay:.3f} s -> {proc.returncode}: {head[:300]}", file=sys.stderr, flush=True)
        shutil.rmtree(out, ignore_errors=True)
        if (i + 1) % 50 == 0:
            bad = sum(n for c in counts.values() for k, n in c.items() if k not in ("ok", "early"))
            print(f"stress_signals: {i + 1}/{runs} runs, {bad} not ok", file=sys.stderr,
                  flush=True)
    return {"runs": runs, "seed": seed, "windows_s": {k: round(v, 3) for k, v in windows.items()},
            "counts": {k: dict(v) for k, v in counts.items()},
            "statuses": {k: dict(v) for k, v in statuses.items()}, "crashes": crashes}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", help="write the whole result (every crash's stderr) here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="stress-signals-") as scratch:
        result = stress(args.runs, args.seed, Path(scratch))
    for name, count in result["counts"].items():
        print(f"{name:18s} {dict(count)} statuses {result['statuses'][name]}")
    for crash in result["crashes"]:
        head = crash["stderr"].strip().splitlines()[:3]
        print(f"{crash['kind']}: {crash['command']} {crash['signal']} after "
              f"{crash['delay_s']} s -> {crash['status']}: {' | '.join(head)}")
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1))
    return 1 if result["crashes"] else 0  # early ones are counted, not kept


if __name__ == "__main__":
    sys.exit(main())
