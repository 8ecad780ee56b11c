"""The README's first two commands are what a new user runs; CI must run the same test command."""

import re
import subprocess
import sys
import textwrap

import pytest
from builders import ROOT


def readme_commands() -> list[str]:
    return re.findall(r"```bash\n(.*?)\n```", (ROOT / "README.md").read_text(), flags=re.S)


def test_readme_starts_with_two_commands():
    text = (ROOT / "README.md").read_text()
    head = text.split("```bash", 1)[0]
    assert head.strip().startswith("# shadowvol") and head.count("\n") <= 3, \
        "the README must start with the two commands"
    commands = readme_commands()
    assert len(commands) >= 2
    assert commands[0].startswith("pip install . &&")
    assert "pytest" in commands[1]


def test_ci_runs_the_readme_test_command():
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert readme_commands()[1] in ci, ".ci/run must run the README's test command verbatim"


def test_readme_links_exist():
    text = (ROOT / "README.md").read_text()
    links = re.findall(r"\]\(([^)#]+)\)", text)
    assert links
    missing = [link for link in links if "://" not in link and not (ROOT / link).exists()]
    assert not missing, f"README links to files that do not exist: {missing}"


@pytest.mark.gl
def test_readme_python_example_runs_from_any_folder(tmp_path):
    """The README's Python example, run as written in a fresh process in an empty folder (at a
    small image size): it may use only the public API and the installed example scenes."""
    block = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)[0]
    line = 'shadowvol.load_scene(shadowvol.example_scene("cage"))'
    assert line in block, "the example no longer loads the installed cage example"
    code = block.replace(line, line + ".replace(width=48, height=36)") + textwrap.dedent("""
        assert frame.lit.shape == lit.shape == (1, 36, 48) and len(frames) == 10
        import numpy as np
        with np.load("cage.npz") as saved:   # the camera matrices the README promises
            assert {"lit", "coverage", "K", "camera_to_world", "world_to_camera"} <= set(saved)
            assert (saved["lit"] == frame.lit).all()
        """)
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cage-copy.toml", "cage.npz",
                                                          "cage.png"]


def test_ci_runs_the_readme_first_command_in_a_fresh_venv():
    """.ci/run takes the README's first command from the README itself (so the two cannot drift)
    and runs it in a venv it has just made, before the suite."""
    ci = (ROOT / ".ci" / "run").read_text()
    assert "-m venv" in ci and 'bash -c "$first"' in ci
    extract = re.search(r"first=\"\$\(python3 -c '(.*)'\)\"", ci)
    assert extract, ".ci/run no longer extracts the first command from the README"
    done = subprocess.run([sys.executable, "-c", extract.group(1)], cwd=ROOT, capture_output=True,
                          text=True, timeout=60)
    assert done.stdout.strip() == readme_commands()[0]
    assert ci.index('bash -c "$first"') < ci.index(readme_commands()[1])
