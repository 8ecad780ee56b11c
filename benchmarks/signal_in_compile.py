"""Reproducer (not a test): SIGINT or SIGTERM while moderngl links a shader program, the moment
of the SIGSEGV that `benchmarks/stress_signals.py` caught once in 1,200 runs.

    python -m benchmarks.signal_in_compile [--signals 300] [--runs 5] [--seed 0]

Each run starts a child that makes a GL context and, inside `shadowvol.signals.handled`, links
the scene's G-buffer program (`glsl.program(ctx, "scene.vert", "gbuffer.frag")`, as
`Renderer(scene)` does) again and again, catching the KeyboardInterrupt / Terminated each signal
raises and going on.  The parent sends it SIGINT or SIGTERM at random moments, spread over the
time one link takes, up to `--signals` of them, then ends it with SIGUSR1 (exit 0).  Each run
ends `ok` (status 0: every signal answered, the child alive) or `crash` (killed by a signal the
parent did not send: -11 SIGSEGV, ..., or hung) or `escaped` (an interrupt got out of the
child's loop between two of its lines, rare: the child's limit, not a crash), with the count of
signals sent.

Why that moment: moderngl's `Context.program` (C) calls back into Python (`_moderngl`'s
`make_attribute`, `make_uniform`, ...) for each of the program's attributes and uniforms and
does not check what comes back.  A signal that arrives while the driver links (no Python runs
then) is answered by Python's handler at the first bytecode after it, the first line of that
callback; a handler that raises there makes the callback return NULL, which moderngl stores
and dereferences: SIGSEGV in the main thread, `ctx.program` on top of the stack.
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import time

CHILD = """
import os, signal, sys, time
from shadowvol import signals
from shadowvol.raster import glsl
from shadowvol.raster.platform.context import create_context
ctx = create_context()
signal.signal(signal.SIGUSR1, lambda *a: os._exit(0))  # the parent's "enough"
with signals.handled():
    start = time.perf_counter()
    for _ in range(5):
        glsl.program(ctx, "scene.vert", "gbuffer.frag").release()
    print((time.perf_counter() - start) / 5, flush=True)  # one link's time: ready
    while True:  # three levels: one that lands between two lines of a level is caught too
        try:
            try:
                while True:
                    try:
                        glsl.program(ctx, "scene.vert", "gbuffer.frag").release()
                    except (KeyboardInterrupt, signals.Terminated):
                        pass
            except (KeyboardInterrupt, signals.Terminated):
                pass
        except (KeyboardInterrupt, signals.Terminated):
            pass
"""


def one_run(signals: int, rng: random.Random) -> tuple[int, int, str]:
    """(status, signals sent, stderr's last lines) of one child."""
    env = dict(os.environ, PYTHONFAULTHANDLER="1")
    proc = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    link_s = float(proc.stdout.readline() or "nan")
    time.sleep(0.05)  # into its loop
    sent = 0
    while sent < signals and proc.poll() is None and link_s == link_s:
        time.sleep(rng.uniform(0.0, 2.0 * link_s))
        proc.send_signal(rng.choice((signal.SIGINT, signal.SIGTERM)))
        sent += 1
    time.sleep(0.1)  # a signal still being answered (re-sent after signals.REDELIVER_S)
    if proc.poll() is None:
        proc.send_signal(signal.SIGUSR1)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        err = "HUNG\n" + err
    return proc.returncode, sent, err


def classify(code: int, err: str) -> str:
    """`ok` (status 0), `crash` (killed by a signal the parent did not send, a fatal error, a
    hang) or `escaped` (an interrupt got out of the child's loop, which then ended by it: the
    loop's own limit, no crash)."""
    if code == 0:
        return "ok"
    if code in (-signal.SIGINT, -signal.SIGTERM, 130, 143, 1) and "Fatal Python" not in err \
            and not err.startswith("HUNG"):
        return "escaped"
    return "crash"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--signals", type=int, default=300, help="signals per run at most")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rng = random.Random(args.seed)
    crashes = 0
    total = 0
    for i in range(args.runs):
        code, sent, err = one_run(args.signals, rng)
        total += sent
        kind = classify(code, err)
        crashes += kind == "crash"
        tail = " | ".join(err.strip().splitlines()[-6:]) if kind != "ok" else ""
        print(f"run {i}: {kind} (status {code}) after {sent} signals {tail}"[:400], flush=True)
    print(f"{args.runs} runs, {total} signals sent, {crashes} crashed (killed by a signal not "
          f"sent, a fatal error or a hang)")
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
