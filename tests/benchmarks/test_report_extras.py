"""benchmarks.report: the other benchmark modules' outputs (`processes.EXTRAS`) go to pages of
their own beside the plot, verbatim, each linked from the markdown by a path that resolves, so
that BENCHMARKS.md stays within its line limit however much they print.  Nothing is timed."""

from __future__ import annotations

import re

from benchmarks import processes
from benchmarks.report import summary


def fake_results() -> dict:
    output = "\n".join(f"| row {i} | {i * 1.5:.1f} |" for i in range(200))
    return {"machine": {"commit": "abc1234", "date": "2026-12-05 06:00 UTC"},
            "extras": [{"script": "bench_packets.py",
                        "command": "python -m benchmarks.bench_packets", "what": "packets against single rays", "seconds": 12.3, "returncode": 0,
                        "output": output, "results": None},
                       {"script": "bench_viewer.py", "command": "python -m benchmarks.bench_viewer",
                        "what": "the viewer", "seconds": 900.0, "returncode": None,
                        "output": "timed out after 900 s", "results": None}]}


def test_each_extra_is_a_page_beside_the_plot_linked_from_the_markdown(tmp_path):
    results, md, png = fake_results(), tmp_path / "BENCHMARKS.md", tmp_path / "benchmarks.png"
    lines = summary.extras(results, md, png)
    written = summary.write_extras(results, md, png)
    assert [p.name for p in written] == ["bench_packets.md", "bench_viewer.md"]
    assert all(p.parent == tmp_path / "benchmarks" for p in written)
    assert len(lines) < 10   # a line an extra, not its output
    links = re.findall(r"\]\(([^)]+\.md)\)", "\n".join(lines))
    assert [(md.parent / link).resolve() for link in links] == [p.resolve() for p in written]
    page = written[0].read_text()
    assert results["extras"][0]["output"] in page and "commit abc1234" in page
    assert "12 s, ok." in page and "timed out." in written[1].read_text()
    back = re.search(r"\[BENCHMARKS\.md\]\(([^)]+)\)", page).group(1)
    assert (written[0].parent / back).resolve() == md.resolve()


def test_the_full_run_writes_them_to_docs_benchmarks():
    root = summary.OPTIMISATIONS.parents[1]
    assert summary.extras_folder(root / "docs" / "benchmarks.png") == root / "docs" / "benchmarks"


def test_the_run_records_the_packets_the_peers_and_auto_s_choice():
    scripts = [script for script, _, _ in processes.EXTRAS]
    for script in ("bench_packets.py", "bench_peers.py", "bench_fastest.py"):
        assert script in scripts
        assert (summary.OPTIMISATIONS.parent / script).is_file()
