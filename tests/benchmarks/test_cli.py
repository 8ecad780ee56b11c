"""benchmarks.cli: the measuring benchmarks' shared command line."""

import json

import pytest

from benchmarks.cli import bench_main, load_span


def test_runs_json_load_and_report(tmp_path, capsys):
    out = tmp_path / "r.json"
    seen = {}

    def measure(args):
        seen["runs"] = args.runs
        return {"value": 3}

    assert bench_main(["--runs", "2", "--json", str(out)], "bench_x", "First.\n\nMore.",
                      measure, lambda r, a: f"{a.runs} rounds; {load_span(r)}") == 0
    written = json.loads(out.read_text())
    assert seen == {"runs": 2} and written["value"] == 3
    assert len(written["load"]) == 2 and all(len(x) == 3 for x in written["load"])
    assert capsys.readouterr().out.startswith("2 rounds; load ")


def test_own_load_kept_and_quick_only_when_asked(capsys):
    mine = {"load": [[9.0, 0, 0], [8.0, 0, 0]]}
    bench_main([], "bench_x", "Doc.", lambda a: dict(mine, quick=a.quick),
               lambda r, a: load_span(r), quick=True)
    assert capsys.readouterr().out.strip() == "load 9.0 -> 8.0"
    with pytest.raises(SystemExit):
        bench_main(["--quick"], "bench_x", "Doc.", lambda a: {}, lambda r, a: "")
