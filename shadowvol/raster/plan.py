"""`FramePlan`: what one frame draws and reads, decided once from `Renderer.render`'s arguments."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class FramePlan:
    """method : "auto" | "zpass" | "zfail".  asked : the outputs named by the caller (with "lit"
    when the overflow check needs it); outputs : those and what they need ("facing" for
    casters and facing_count).  halve : `auto`'s z-pass casters may be drawn m / 2 times,
    which is safe only when the counts themselves are not returned
    (`passes.count_signed`)."""

    method: str
    asked: frozenset[str]
    outputs: frozenset[str]
    want_stencil: bool
    halve: bool
    facing_pass: bool   # facing (and casters) need the facing pass; it gives the lit bits too

    @classmethod
    def of(cls, method: str, asked: set[str]) -> "FramePlan":
        needs_facing = bool({"casters", "facing_count"} & asked)
        outputs = asked | {"facing"} if needs_facing else asked
        want_stencil = "stencil" in outputs
        return cls(method, frozenset(asked), frozenset(outputs), want_stencil,
                   halve=method == "auto" and not want_stencil,
                   facing_pass="facing" in outputs)
