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


def test_readme_links_exist():
    text = (ROOT / "README.md").read_text()
    links = re.findall(r"\]\(([^)#]+)\)", text)
    assert links
    missing = [link for link in links if "://" not in link and not (ROOT / link).exists()]
    assert not missing, f"README links to files that do not exist: {missing}"


def test_readme_python_example_runs(ctx):
    """The README's Python example, run as written (at a small image size)."""
    block = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)[0]
    path = str(ROOT / "scenes" / "cage.toml")
    code = block.replace('load_scene("scenes/cage.toml")',
                         f'load_scene({path!r}).replace(width=48, height=36)')
    assert code != block, "the example no longer loads scenes/cage.toml"
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert namespace["frame"].lit.shape == namespace["lit"].shape == (1, 36, 48)
    assert len(namespace["frames"]) == 10
