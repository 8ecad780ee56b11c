"""What a long batch keeps in memory (issue 36, step 7): a run keeps where each frame's
manifest line is, not the record, so its memory stays flat however many frames it makes
(`benchmarks/bench_batch_memory.py` measures RSS over 10,000 jittered frames); the final
manifest is read back from the journal.  No GL: the frames are ray traced."""

from __future__ import annotations

import json

from builders import SCENES

from shadowvol import batch
from shadowvol.batch import manifest

JOB = {"name": "j", "scene": str(SCENES / "cage.toml"), "size": [4, 3], "outputs": ["masks"],
       "renderer": "raytrace", "max_depth": 0, "jitter": {"eye": 0.1, "lights": 0.1},
       "cameras": {"orbit": {"center": [0, 1, 0], "radius": 6, "frames": 6}}}


def test_a_run_keeps_each_frames_line_not_its_record(tmp_path, monkeypatch):
    kept = []
    finish = manifest.Journal.finish

    def spy(self, records):
        kept.extend(records)
        return finish(self, records)
    monkeypatch.setattr(manifest.Journal, "finish", spy)
    bad = {"name": "bad", "scene": str(SCENES / "cage.toml"), "cameras": []}
    out = tmp_path / "out"
    assert batch.run([bad, JOB], out, progress=False).rendered == 6
    assert isinstance(kept[0], dict) and kept[0]["id"] == "job/bad"   # a bad job: its record
    frames = kept[1:]
    assert len(frames) == 6 and all(type(r).__name__ == "Line" for r in frames), frames
    lines = (out / "manifest.jsonl").read_bytes().splitlines(keepends=True)
    assert [json.loads(line)["id"] for line in lines] == \
        ["job/bad"] + [f"j/{i:06d}" for i in range(6)]
    assert all("files" in json.loads(line) for line in lines[1:])


def test_the_journal_reads_its_lines_back_after_a_cut(tmp_path):
    """A journal opened on a half line a killed run left cuts it; the offsets `add` returns
    are where the lines really are (appended at the file's end, not where it was opened)."""
    path = tmp_path / "manifest.jsonl"
    path.write_bytes(b'{"id": "old"}\n{"id": "half')
    journal = manifest.Journal(path)
    lines = [journal.add({"id": f"n{i}", "pad": "x" * i}) for i in range(3)]
    journal.finish([{"id": "first"}, *reversed(lines)])
    assert [json.loads(x)["id"] for x in path.read_text().splitlines()] == \
        ["first", "n2", "n1", "n0"]
