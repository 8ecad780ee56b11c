"""The README's first two commands are what a new user runs; CI must run the same test command."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


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
