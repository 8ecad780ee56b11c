"""The grader cannot be fooled: plausible student mistakes, each a small edit of the reference
solution, are every one rejected (the task short of full marks); and mutants of the solutions
(one operator or constant flipped, by `ast`) are rejected nearly always.

The broken variants and the mutants are judged in this process (`grader.evaluate`: the same
cases, the same JSON round trip and the same judges as `shadowvol course grade`, without the
per-task process); tests/course/test_assignments.py drives the real command.  The mutation
run takes every mutant up to MUTANTS_CAP (all 290 today, about 5 s), a seeded sample past it;
SHADOWVOL_LONG=1 runs every one whatever their number.

Kill rate: 254 of the 290 mutants (87.6 %) are rejected.  The 36 survivors change nothing the
cases can fairly ask: a `<` made `<=` (or `>` made `>=`) where no case sits exactly on the
boundary, because the answer there would hang on rounding (the shadow ray's λ = 0 after its
offset, a tangent shadow ray, a side of the volume through P or the eye, k = 0 at the critical
angle, where both answers are accepted); a factor moved to the other side of a sign test
(`* uv` made `/ uv`); a perimeter parameter taken mod −4 instead of 4, or shifted by 4; the
2D exercise's tolerance scaled by a segment's length.
"""

from __future__ import annotations

import ast
import os
import random

import numpy as np
import pytest

from shadowvol.course import grader
from shadowvol.course.workspace import solution_source, write_workspace

TASKS = {t.name: t for t in grader.TASKS}

# (task, mistake, text of the solution, what the student wrote instead)
BROKEN = [
    ("ray_plane", "no λ > 0 test", "return lam if lam > 0.0 else None", "return lam"),
    ("ray_plane", "λ >= 0: the origin on the plane counts as a hit", "lam > 0.0", "lam >= 0.0"),
    ("ray_plane", "no test for a parallel ray", "    if n_dot_r == 0.0:\n        return None\n",
     ""),
    ("ray_plane", "d − n·o with the sign turned", "float(n @ (a - o))", "float(n @ (o - a))"),
    ("ray_sphere", "the far root", "    if near > 0.0:\n        return near\n", ""),
    ("ray_sphere", "no λ > 0 test: the near root always",
     "    if near > 0.0:\n        return near\n    if far > 0.0:\n        return far\n"
     "    return None", "    return near"),
    ("ray_sphere", "a ray starting inside misses", "    if far > 0.0:\n        return far\n", ""),
    ("ray_sphere", "a grazing ray misses (Δ > 0)", "if disc < 0.0:", "if disc <= 0.0:"),
    ("ray_sphere", "b without its factor 2", "b = 2.0 * float(r @ oc)", "b = float(r @ oc)"),
    ("ray_triangle", "the edges excluded", "beta >= 0.0 and gamma >= 0.0 and beta + gamma <= 1.0",
     "beta > 0.0 and gamma > 0.0 and beta + gamma < 1.0"),
    ("ray_triangle", "β and γ swapped", "return lam, beta, gamma", "return lam, gamma, beta"),
    ("ray_triangle", "no β + γ <= 1 test", " and beta + gamma <= 1.0", ""),
    ("ray_triangle", "no λ > 0 test", "    if lam <= 0.0:\n        return None\n", ""),
    ("ray_triangle", "α given for β", "return lam, beta, gamma", "return lam, 1 - beta - gamma, gamma"),
    ("reflection", "+2(n·d)n", "return d - 2.0 *", "return d + 2.0 *"),
    ("reflection", "the factor 2 missing", "d - 2.0 * float(n @ d) * n", "d - float(n @ d) * n"),
    ("reflection", "the normal not normalised", "    n = n / np.linalg.norm(n)\n", ""),
    ("reflection", "the result normalised", "    return d - 2.0 * float(n @ d) * n",
     "    r = d - 2.0 * float(n @ d) * n\n    return r / np.linalg.norm(r)"),
    ("refraction", "n1 and n2 swapped", "eta = n1 / n2", "eta = n2 / n1"),
    ("refraction", "total internal reflection ignored (k clamped at 0)",
     "    if k < 0.0:\n        return d - 2.0 * float(n @ d) * n, True\n", "    k = max(k, 0.0)\n"),
    ("refraction", "+√k", "(eta * cos1 - math.sqrt(k))", "(eta * cos1 + math.sqrt(k))"),
    ("refraction", "cos θ1 = n·d (the sign)", "cos1 = -float(n @ d)", "cos1 = float(n @ d)"),
    ("refraction", "TIR flagged, the ray passed on unchanged",
     "return d - 2.0 * float(n @ d) * n, True", "return d, True"),
    ("shadow_ray", "no offset on the shadow ray", "OFFSET = 1e-6", "OFFSET = 0.0"),
    ("shadow_ray", "hits beyond the light count", "if 0.0 < lam < 1.0:", "if 0.0 < lam:"),
    ("shadow_ray", "hits behind the start count", "if 0.0 < lam < 1.0:", "if lam < 1.0:"),
    ("shadow_ray", "the offset into the surface", "start = p + OFFSET * n",
     "start = p - OFFSET * n"),
    ("phong", "no test n·l > 0", "    if n_dot_l <= 0.0:\n        return colour\n", ""),
    ("phong", "r·v not clamped", "max(float(r @ v), 0.0)", "float(r @ v)"),
    ("phong", "r mirrored the wrong way", "r = 2.0 * n_dot_l * n - l", "r = l - 2.0 * n_dot_l * n"),
    ("phong", "Blinn's half vector for r·v", "r_dot_v = max(float(r @ v), 0.0)",
     "h = (l + v) / np.linalg.norm(l + v)\n    r_dot_v = max(float(n @ h), 0.0)"),
    ("phong", "no ambient term", "colour = np.asarray(ka, float) * np.asarray(ambient, float)",
     "colour = np.zeros(3)"),
    ("shadow_region", "the square's corners left out",
     "            region.append(np.asarray(CORNERS[k]))", "            pass"),
    ("shadow_region", "clockwise", "    return out\n", "    return out[::-1]\n"),
    ("shadow_region", "back-facing segments cast nothing",
     "    p, q = (a, b) if side > 0 else (b, a)\n",
     "    if side < 0:\n        return []\n    p, q = a, b\n"),
    ("shadow_region", "the light on the segment's line not caught",
     "    if abs(side) <= ON_LINE:\n        return []\n", ""),
    ("silhouette", "the sign of det[b − a, c − a, a − L]", "@ (L - v[i])", "@ (v[i] - L)"),
    ("silhouette", "the edge's direction in the winding ignored", "(sign if s < e else -sign)",
     "sign"),
    ("silhouette", "back-facing triangles cast nothing",
     "        for s, e in ((i, j), (j, k), (k, i)):",
     "        if sign < 0:\n            continue\n        for s, e in ((i, j), (j, k), (k, i)):"),
    ("silhouette", "|m|", "return {key: m for", "return {key: abs(m) for"),
    ("silhouette", "edges not keyed a < b", "key = (min(s, e), max(s, e))", "key = (s, e)"),
    ("zcount", "the z-pass sign flipped", "zpass = sum(", "zpass = -sum("),
    ("zcount", "the far cap forgotten", "        steps.append((np.inf, -1))", "        pass"),
    ("zcount", "z-fail counted between the eye and P",
     "zfail = -sum(step for t, step in steps if t > 1)",
     "zfail = sum(step for t, step in steps if t < 1)"),
    ("zcount", "every edge a near cap", "        if facing[-1]:\n", "        if True:\n"),
    ("zcount", "z-fail not negated", "zfail = -sum(", "zfail = sum("),
    ("planar", "P Lᵀ for L Pᵀ", "np.outer(L, P)", "np.outer(P, L)"),
    ("planar", "no sign(P·L)", "return np.sign(p_dot_l) * M", "return M"),
    ("planar", "d = +n·a", "-float(n @ np.asarray(plane_point, float))",
     "float(n @ np.asarray(plane_point, float))"),
    ("planar", "the normal not normalised", "    n = n / np.linalg.norm(n)\n", ""),
]


def _function(task_name: str, source: str):
    namespace = {"__name__": f"student_{task_name}"}
    exec(compile(source, f"{task_name}.py", "exec"), namespace)   # noqa: S102 - our own text
    return namespace[TASKS[task_name].function]


def test_every_task_has_three_broken_variants():
    per_task = {name: sum(1 for t, *_ in BROKEN if t == name) for name in TASKS}
    assert min(per_task.values()) >= 3, per_task


@pytest.mark.parametrize("task_name, mistake, right, wrong", BROKEN,
                         ids=[f"{t}: {m}" for t, m, *_ in BROKEN])
def test_a_broken_variant_is_rejected(task_name, mistake, right, wrong):
    source = solution_source(task_name)
    assert source.count(right) == 1, f"the solution no longer holds {right!r}"
    result = grader.evaluate(TASKS[task_name], _function(task_name, source.replace(right, wrong)))
    assert result.passed < result.total, f"{task_name}: '{mistake}' got full marks"
    assert result.failure and "expected" in result.failure


def test_the_real_grader_rejects_them_too(tmp_path):
    """The first mistake of every task, handed in as files and graded by the command's own
    path (a process per task): every task short of full marks, the others untouched."""
    write_workspace(tmp_path / "ws", solved=True)
    first = {}
    for task_name, mistake, right, wrong in BROKEN:
        first.setdefault(task_name, (mistake, right, wrong))
    for task_name, (_, right, wrong) in first.items():
        path = tmp_path / "ws" / f"{task_name}.py"
        path.write_text(path.read_text().replace(right, wrong))
    report = grader.grade(tmp_path / "ws")
    assert {r.task.name for r in report.results if r.passed < r.total} == set(TASKS)


# ---------------------------------------------------------------------------------------------
# Mutation: one operator or constant of a solution flipped
# ---------------------------------------------------------------------------------------------

SWAP = {ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult,
        ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt, ast.Eq: ast.NotEq,
        ast.NotEq: ast.Eq, ast.And: ast.Or, ast.Or: ast.And}
MUTANTS_CAP = 400
KILL_RATE = 0.85   # measured: 0.876; see the module's docstring
LONG = os.environ.get("SHADOWVOL_LONG") == "1"


def _sites(tree) -> list[tuple[int, str]]:
    """(index of the node in ast.walk order, what to do) for every mutable spot of the graded
    code (the functions' bodies, docstrings and module constants left alone)."""
    out = []
    functions = [n for n in tree.body if isinstance(n, ast.FunctionDef)]
    inside = {id(x) for f in functions for stmt in f.body[1:] for x in ast.walk(stmt)}
    # indices are left alone: in 2D x[-1] is x[1], a mutant no case can tell apart
    inside -= {id(n.slice) for n in ast.walk(tree) if isinstance(n, ast.Subscript)}
    for k, node in enumerate(ast.walk(tree)):
        if id(node) not in inside:
            continue
        if isinstance(node, (ast.BinOp, ast.BoolOp)) and type(node.op) in SWAP:
            out.append((k, "op"))
        elif isinstance(node, ast.Compare) and type(node.ops[0]) in SWAP:
            out.append((k, "compare"))
        elif isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
                and not isinstance(node.value, bool):
            out.append((k, "negate" if node.value else "one"))
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            out.append((k, "drop minus"))
    return out


def _mutant(source: str, site: tuple[int, str]) -> str:
    tree = ast.parse(source)
    nodes = list(ast.walk(tree))
    k, how = site
    node = nodes[k]
    if how == "op":
        node.op = SWAP[type(node.op)]()
    elif how == "compare":
        node.ops[0] = SWAP[type(node.ops[0])]()
    elif how == "negate":
        node.value = -node.value
    elif how == "one":
        node.value = 1
    else:   # drop a unary minus: replace the UnaryOp by its operand
        for parent in nodes:
            for field, value in ast.iter_fields(parent):
                if value is node:
                    setattr(parent, field, node.operand)
                elif isinstance(value, list) and any(v is node for v in value):
                    value[[i for i, v in enumerate(value) if v is node][0]] = node.operand
    return ast.unparse(ast.fix_missing_locations(tree))


def _all_mutants() -> list[tuple[str, tuple[int, str]]]:
    return [(name, site) for name in TASKS for site in _sites(ast.parse(solution_source(name)))]


def test_mutants_of_the_solutions_are_rejected():
    every = _all_mutants()
    chosen = every if LONG or len(every) <= MUTANTS_CAP else \
        random.Random(42).sample(every, MUTANTS_CAP)
    cases = {name: TASKS[name].cases() for name in TASKS}
    survivors = []
    for name, site in chosen:
        try:
            function = _function(name, _mutant(solution_source(name), site))
            with np.errstate(all="ignore"):   # a mutant dividing by zero: judged by its answer
                result = grader.evaluate(TASKS[name], function, cases[name])
        except Exception:   # noqa: BLE001 - a mutant that does not even load is killed
            continue
        if result.passed == result.total:
            survivors.append((name, site))
    rate = 1 - len(survivors) / len(chosen)
    print(f"\nmutation: {len(chosen)} of {len(every)} mutants, killed {rate:.1%}; survivors: "
          f"{survivors}")
    assert rate >= KILL_RATE, f"only {rate:.1%} of the mutants rejected; survivors {survivors}"

