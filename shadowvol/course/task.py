"""A graded task of the course's exercises: its hidden cases, how an answer is judged and how
a case is put in words a student understands.

A `Case` holds the arguments the student's function is called with (plain JSON: lists, numbers,
None) and the answer the project's own implementation gives (`tasks_rays`, `tasks_shadows`).
A judge compares the student's answer, as it comes back from the grading process (JSON again),
with the expected one, and says what is wrong in one sentence, or None when it is right.

Tolerances.  Every case's numbers are of order 1 to 10 and its geometry well conditioned (no
hit closer than 1e-3 to a miss, except the exact tangent and edge cases, whose inputs are small
dyadic numbers that float64 computes exactly), so two correct formulas agree to about 1e-14
relative (the reference solutions are at most 3e-16 off the witness; a test checks 1e-13).  The plausible mistakes move an answer by 1e-3 or more.  `TOLERANCE` = 1e-9 sits five
orders from both: relative to 1 + |expected|, per number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

TOLERANCE = 1e-9


@dataclass(frozen=True)
class Case:
    """One hidden case: `label` says what it tries (the edge it probes), `args` the function's
    arguments (JSON-able), `expected` the witness's answer, `alternatives` other answers that
    are right too (exactly at the critical angle, where rounding decides)."""

    label: str
    args: tuple
    expected: object
    alternatives: tuple = ()


@dataclass(frozen=True)
class Task:
    """One exercise: the workspace module `name`.py with the function `function`.

    judge(expected, got) -> None when right, else why not (a sentence);
    show_args(args) -> the inputs in words; show(value) -> an answer in words; `explains`:
    whether the judge's sentence says more than the expected and the got do (which component
    of a vector, which edge) and is worth a line of the table."""

    name: str
    function: str
    title: str
    points: int
    cases: Callable[[], list[Case]]
    judge: Callable[[object, object], str | None]
    show_args: Callable[[tuple], str]
    show: Callable[[object], str] = field(default=lambda v: show_value(v))
    explains: bool = True

    def check(self, case: Case, got) -> str | None:
        """None when `got` is right for `case` (its answer or an alternative), else why not."""
        why = self.judge(case.expected, got)
        if why is None or any(self.judge(alt, got) is None for alt in case.alternatives):
            return None
        return why


# ---------------------------------------------------------------------------------------------
# Numbers in words
# ---------------------------------------------------------------------------------------------

def num(x) -> str:
    """A number as the table prints it: up to 6 significant digits."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return repr(x)
    return f"{x:.6g}"


def vec(v) -> str:
    """A vector as "(x, y, z)"."""
    if not isinstance(v, (list, tuple)):
        return show_value(v)
    return "(" + ", ".join(num(x) if not isinstance(x, (list, tuple)) else vec(x)
                           for x in v) + ")"


def show_value(v) -> str:
    if v is None:
        return "None"
    if isinstance(v, (list, tuple)):
        return vec(v)
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {show_value(x)}" for k, x in v.items()) + "}"
    return num(v)


# ---------------------------------------------------------------------------------------------
# Judging
# ---------------------------------------------------------------------------------------------

def is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def close(expected: float, got: float, tolerance: float = TOLERANCE) -> bool:
    return is_number(got) and math.isfinite(got) and \
        abs(got - expected) <= tolerance * (1.0 + abs(expected))


def judge_vector(expected, got, what: str = "the vector") -> str | None:
    """A vector of numbers, each within TOLERANCE."""
    if not isinstance(got, list) or not all(is_number(x) for x in got):
        return f"expected {what} as a sequence of numbers, got {show_value(got)}"
    if len(got) != len(expected):
        return f"{what} has {len(got)} numbers, expected {len(expected)}"
    for i, (e, g) in enumerate(zip(expected, got)):
        if not close(e, g):
            return f"{what}'s component {i} is {num(g)}, expected {num(e)}"
    return None


def judge_lambda(expected, got) -> str | None:
    """A ray parameter λ (a number) or None for a miss."""
    if expected is None:
        return None if got is None else f"expected no hit (None), got λ = {show_value(got)}"
    if got is None:
        return f"expected a hit at λ = {num(expected)}, got None (a miss)"
    if not is_number(got):
        return f"expected λ as a number, got {show_value(got)}"
    return None if close(expected, got) else f"λ = {num(got)}, expected {num(expected)}"


def judge_exact(expected, got) -> str | None:
    """Booleans and whole numbers: equal, nothing less."""
    if type(got) is not type(expected) and not (is_number(got) and is_number(expected)):
        return f"expected {show_value(expected)}, got {show_value(got)} ({type(got).__name__})"
    return None if got == expected else f"expected {show_value(expected)}, got {show_value(got)}"
