"""The command line the measuring benchmarks share: `--runs`, `--json`, the load before and
after, the table printed (`bench_packets`, `bench_single_masks`, `bench_open3d`,
`bench_peers`)."""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Callable


def bench_main(argv, module: str, doc: str, measure: Callable[[argparse.Namespace], dict],
               report: Callable[[dict, argparse.Namespace], str], quick: bool = False) -> int:
    """Run the benchmark module `module` as its own command: parse --runs (default 5),
    --json FILE (every number written there) and, with `quick`, --quick; `measure(args)` gives
    the result, which gets the load average before and after unless it holds its own
    ("load"); print `report(result, args)`.  The description is the first paragraph of the
    module's `doc`."""
    ap = argparse.ArgumentParser(prog=f"python -m benchmarks.{module}",
                                 description=doc.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    if quick:
        ap.add_argument("--quick", action="store_true",
                        help="a smoke run: tiny scenes, one round")
    ap.add_argument("--json", type=Path, help="write every number here")
    args = ap.parse_args(argv)
    load = os.getloadavg()
    result = measure(args)
    result.setdefault("load", [load, os.getloadavg()])
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    print(report(result, args))
    return 0


def load_span(result: dict) -> str:
    """'load A -> B' from a result's load averages before and after."""
    before, after = result["load"]
    return f"load {before[0]:.1f} -> {after[0]:.1f}"
