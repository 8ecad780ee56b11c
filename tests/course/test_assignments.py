"""`shadowvol course new|grade|solutions`, driven as a teacher drives it: a new workspace
grades 0 and exits 1, the reference solutions grade full marks and exit 0, an endless loop or
a crash costs its task only, bad input is one line and exit 2; and the reference solutions
agree with the witness far inside the grader's tolerance."""

from __future__ import annotations

import doctest
import importlib.util
import json
import math
import re
from pathlib import Path

import pytest

from shadowvol.cli import status
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.course import grader
from shadowvol.course.runner import plain
from shadowvol.course.task import TOLERANCE
from shadowvol.course.workspace import SOLUTIONS, solution_source, stub

TASKS = {t.name: t for t in grader.TASKS}


def test_a_new_workspace_grades_zero_and_exits_1(tmp_path, capsys):
    ws, out = tmp_path / "ws", tmp_path / "results.json"
    assert shadowvol_main(["course", "new", str(ws)]) == status.OK
    assert sorted(p.name for p in ws.iterdir()) == sorted(
        [f"{t}.py" for t in TASKS] + ["README.md"])
    assert shadowvol_main(["course", "grade", str(ws), "--json", str(out)]) == 1
    table = capsys.readouterr().out
    total = sum(t.points for t in TASKS.values())
    assert f"total0/{total}" in table.replace(" ", "")
    results = json.loads(out.read_text())
    assert results["score"] == 0 and results["max_score"] == sum(t.points for t in TASKS.values())
    assert len(results["tests"]) == len(TASKS) >= 10
    assert all(t["score"] == 0 and "NotImplementedError" in t["output"]
               for t in results["tests"])


def test_the_solutions_grade_full_marks_and_exit_0(tmp_path, capsys):
    sol, out = tmp_path / "sol", tmp_path / "results.json"
    assert shadowvol_main(["course", "solutions", str(sol)]) == status.OK
    assert shadowvol_main(["course", "grade", str(sol), "--json", str(out)]) == status.OK
    table = capsys.readouterr().out
    total = sum(t.points for t in TASKS.values())
    assert f"{total}/{total}" in table.replace(" ", "")
    results = json.loads(out.read_text())
    assert results["score"] == results["max_score"] == total
    assert {t["name"].split(":")[0] for t in results["tests"]} == set(TASKS)
    assert all(set(t) == {"name", "score", "max_score", "output"} for t in results["tests"])


def test_an_endless_loop_or_a_crash_costs_only_its_task(tmp_path):
    ws = tmp_path / "ws"
    assert shadowvol_main(["course", "solutions", str(ws)]) == status.OK
    sphere = solution_source("ray_sphere").replace('    o, r, c = (', '    while True:\n'
                                                   '        pass\n    o, r, c = (')
    (ws / "ray_sphere.py").write_text(sphere)
    (ws / "reflection.py").write_text("import os\n\ndef reflect(d, n):\n    os._exit(3)\n")
    (ws / "planar.py").write_text("def projection_matrix(p, n, L):\n    return [[1, 2\n")
    (ws / "phong.py").unlink()
    (ws / "ray_plane.py").write_text(solution_source("ray_plane").replace(
        "    n_dot_r = float(n @ r)\n", "    n_dot_r = float(n @ r)\n    print('debug', n_dot_r)\n"
        "    if n_dot_r < 0:\n        raise ValueError('a student bug')\n"))
    names = ["ray_sphere", "reflection", "planar", "phong", "ray_plane", "ray_triangle",
             "zcount"]
    report = grader.grade(ws, timeout=4.0, tasks=[TASKS[n] for n in names])
    got = {r.task.name: r for r in report.results}
    assert "time limit of 4 s" in got["ray_sphere"].failure
    assert "died (exit status 3)" in got["reflection"].failure
    assert "SyntaxError" in got["planar"].failure and "importing planar.py" in \
        got["planar"].failure
    assert got["phong"].failure == "phong.py is missing"
    for name in ("ray_sphere", "reflection", "planar", "phong"):
        assert got[name].passed == 0 and got[name].score == 0
    assert 0 < got["ray_plane"].passed < got["ray_plane"].total     # one case's error: one case
    assert "raised ValueError: a student bug" in got["ray_plane"].failure
    for name in ("ray_triangle", "zcount"):
        assert got[name].passed == got[name].total
    assert not report.full_marks


def test_a_student_cannot_call_the_witness(tmp_path):
    ws = tmp_path / "ws"
    assert shadowvol_main(["course", "solutions", str(ws)]) == status.OK
    (ws / "ray_plane.py").write_text(
        "def intersect(o, r, a, n):\n"
        "    from raytrace.exercise import solve_plane\n"
        "    lam = solve_plane(o, r, a, n).lam\n"
        "    return lam if lam != float('inf') else None\n")
    result = grader.grade(ws, tasks=[TASKS["ray_plane"]]).results[0]
    assert result.passed == 0 and "raytrace is not available while grading" in \
        result.failure


def test_the_table_names_the_first_failing_case_in_words(tmp_path):
    ws = tmp_path / "ws"
    assert shadowvol_main(["course", "solutions", str(ws)]) == status.OK
    (ws / "ray_sphere.py").write_text(solution_source("ray_sphere").replace(
        "    if near > 0.0:\n        return near\n", ""))
    text = grader.table(grader.grade(ws, tasks=[TASKS["ray_sphere"]]))
    assert "case 1 of" in text and "a ray from outside, head-on" in text
    assert "input:    ray (0, 0, -5) + λ (0, 0, 1), sphere centre (0, 0, 0) radius 1" in text
    assert "expected: λ = 4" in text and "got:      λ = 6" in text


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "mine.txt").write_text("keep me")
    assert shadowvol_main(["course", "new", str(tmp_path / "full")]) == status.BAD_INPUT
    assert (tmp_path / "full" / "mine.txt").read_text() == "keep me"
    assert shadowvol_main(["course", "solutions", str(tmp_path / "full")]) == status.BAD_INPUT
    assert shadowvol_main(["course", "grade", str(tmp_path / "nowhere")]) == status.BAD_INPUT
    assert shadowvol_main(["course", "grade", str(tmp_path / "full")]) == status.BAD_INPUT
    assert shadowvol_main(["course", "grade", str(tmp_path / "full"), "--json",
                           str(tmp_path / "r.txt")]) == status.BAD_INPUT
    for timeout in ("0", "nan", "inf", "-3"):
        assert shadowvol_main(["course", "grade", str(tmp_path / "full"), "--timeout",
                               timeout]) == status.BAD_INPUT
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 9 and all("--timeout must be" in line for line in err[5:])
    err = err[:5]
    assert len(err) == 5 and all(line.startswith("error: ") for line in err), err
    assert "not empty" in err[0] and "no such folder" in err[2] and \
        "not a course workspace" in err[3] and "must end in .json" in err[4]


# ---------------------------------------------------------------------------------------------
# The workspace's modules
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(TASKS))
def test_a_stub_raises_and_keeps_its_docstring_and_example(name, tmp_path):
    path = tmp_path / f"{name}.py"
    path.write_text(stub(solution_source(name)))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    function = getattr(module, TASKS[name].function)
    assert ">>> " in function.__doc__ and "Output" in function.__doc__
    with pytest.raises(NotImplementedError):
        function(*TASKS[name].cases()[0].args)
    assert not [n for n in vars(module) if n.startswith("_") and callable(vars(module)[n])]


@pytest.mark.parametrize("name", sorted(TASKS))
def test_a_solutions_example_is_right(name):
    spec = importlib.util.spec_from_file_location(name, SOLUTIONS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    failed, tried = doctest.testmod(module, verbose=False)
    assert tried >= 1 and failed == 0


def _numbers(value):
    if isinstance(value, dict):
        value = value.get("pairs", [])
    if isinstance(value, (list, tuple)):
        for v in value:
            yield from _numbers(v)
    elif isinstance(value, float):
        yield value


@pytest.mark.parametrize("name", sorted(TASKS))
def test_the_solutions_agree_with_the_witness_far_inside_the_tolerance(name):
    """The margin that justifies TOLERANCE: two correct formulas differ by rounding only."""
    task = TASKS[name]
    spec = importlib.util.spec_from_file_location(name, SOLUTIONS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    cases = task.cases()
    assert len(cases) >= 10
    result = grader.evaluate(task, getattr(module, task.function), cases)
    assert result.passed == result.total, result.failure
    worst = 0.0
    for case in cases:
        got = plain(getattr(module, task.function)(*case.args))
        expected = case.expected
        if case.alternatives and task.judge(expected, got) is not None:
            expected = case.alternatives[0]
        pairs = list(zip(_numbers(expected), _numbers(got)))
        worst = max([worst] + [abs(e - g) / (1 + abs(e)) for e, g in pairs if math.isfinite(e)])
    assert worst <= TOLERANCE / 1e4, f"{name}: the solution is {worst:.1e} off the witness"


def test_the_cases_hold_the_edges_the_lecture_warns_about():
    labels = " | ".join(c.label for t in TASKS.values() for c in t.cases())
    for edge in ("λ < 0", "λ = 0", "grazing", "starting inside the sphere",
                 "exactly at the critical angle", "starts on its own sphere",
                 "eye inside the volume", "the lecture's exercise", "seen from its back"):
        assert edge in labels, edge
    exercise = TASKS["ray_plane"].cases()[0]
    assert exercise.args == ([5.0, 1.0], [-1.0, 3.0], [2.0, 2.0], [1.0, -1.0])
    assert exercise.expected == 1.0


def test_the_docs_table_of_tasks_is_the_graders():
    text = (Path(__file__).resolve().parents[2] / "docs" / "course.md").read_text()
    rows = re.findall(r"^\| (\d+) \| `(\w+)\.py` \| `(\w+)` \| .* \| (\d+) \| (\d+) \| .*\|$", text,
                      re.M)
    assert [(name, function, int(points), int(cases)) for _, name, function, points, cases in rows] \
        == [(t.name, t.function, t.points, len(t.cases())) for t in grader.TASKS]


@pytest.mark.parametrize("argv, words", [
    (["course", "--help"], " ".join(status.EPILOG.split())),
    (["course", "grade", "--help"], "exit status: 0 full marks; 1 short of them; 2 bad input")])
def test_the_help_says_the_statuses(argv, words, capsys):
    with pytest.raises(SystemExit):
        shadowvol_main(argv)
    assert words in " ".join(capsys.readouterr().out.split())


# ---------------------------------------------------------------------------------------------
# The student's code renders
# ---------------------------------------------------------------------------------------------

WHITTED = Path(__file__).resolve().parents[2] / "scenes" / "whitted.toml"


def test_the_students_functions_drive_the_whitted_tracer(tmp_path, capsys):
    ws = tmp_path / "ws"
    assert shadowvol_main(["course", "solutions", str(ws)]) == status.OK
    args = ["course", "render", str(ws), str(WHITTED), "--size", "48x36", "-o"]
    assert shadowvol_main(args + [str(tmp_path / "same.png")]) == status.OK
    assert "0 of 1728 pixels differ" in capsys.readouterr().out
    (ws / "ray_sphere.py").write_text(solution_source("ray_sphere").replace(
        "    if near > 0.0:\n        return near\n", ""))         # the far root
    assert shadowvol_main(args + [str(tmp_path / "far.png")]) == 1
    out = capsys.readouterr().out
    assert int(out.split(" of ")[0]) > 100 and (tmp_path / "far.png").stat().st_size > 0
    (ws / "shadow_ray.py").write_text(stub(solution_source("shadow_ray")))
    (ws / "ray_sphere.py").write_text(solution_source("ray_sphere").replace(
        "    o, r, c = (", "    while True:\n        pass\n    o, r, c = ("))
    assert shadowvol_main(args + [str(tmp_path / "loop.png"), "--timeout", "5"]) == 1
    assert "time limit of 5 s" in capsys.readouterr().out


def test_render_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert shadowvol_main(["course", "render", str(tmp_path / "no"), str(WHITTED), "-o",
                           str(tmp_path / "x.png")]) == status.BAD_INPUT
    assert shadowvol_main(["course", "new", str(tmp_path / "ws")]) == status.OK
    assert shadowvol_main(["course", "render", str(tmp_path / "ws"), str(WHITTED), "-o",
                           str(tmp_path / "x.png"), "--size", "big"]) == status.BAD_INPUT
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 2 and "no such folder" in err[0] and "--size" in err[1], err
