"""Planner repair: failed programs re-parameterised from what the simulator measured.

When no program succeeded in every world, the best failures are looked at in their first failed world:
the first motion call that did not end ``done`` (or, when every call was done, the last one) and the
distances the simulator measured for it (see :data:`~robotool.rollout.DISTANCES`: a gap still too wide,
how far short a motion stopped). Each earlier motion that moved an object (a push) is then tried again
aimed further along its own direction, and less far, by each measured distance plus a margin; the
simulator decides which variant, if any, works. Nothing here names a task or an object kind.
"""

from __future__ import annotations

import numpy as np

from robotool.embodiments import skills
from robotool.planner.codegen import Program
from robotool.rollout import DISTANCES, SkillCall
from robotool.scene import Task
from robotool.solution import Candidate

MARGIN = 0.03  # m added to a measured distance when a target is moved by it
MIN_DISTANCE = 0.01  # m: smaller measured distances say nothing
MOVERS = 2  # object-moving motions before the failure that are re-parameterised (latest first)


def repaired(task: Task, program: Program, candidate: Candidate) -> list[Program]:
    """Variants of ``program`` re-parameterised from ``candidate``'s first failed world (none without evidence)."""
    failed = next((r for r in candidate.rollouts if not r.success), None)
    if failed is None or failed.error is not None:
        return []
    kinds = {s.name: s.kind for s in skills(task.embodiment)}
    motions = [c for c in failed.calls if kinds.get(c.skill) == "motion"]
    failing = next((k for k, c in enumerate(motions) if c.outcome != "done"), len(motions) - 1)
    if failing < 0:
        return []
    distances = _distances(motions[failing])
    movers = [k for k, m in enumerate(program.motions[:failing]) if m.obj is not None and m.point is not None]
    variants = []
    for k in reversed(movers[-MOVERS:]):
        direction = _direction(task, program, k)
        if direction is None:
            continue
        for distance in distances:
            for sign, word in ((1.0, "further"), (-1.0, "less far")):
                shift = sign * (distance + MARGIN) * direction
                why = (
                    f"Re-parameterised from the simulator: {motions[failing].skill} measured {distance:.3f} m, so "
                    f"step {program.motions[k].step} aims {distance + MARGIN:.3f} m {word}."
                )
                variants.append(program.with_target_shifted(k, shift, why))
    return variants


def _distances(call: SkillCall) -> list[float]:
    """The distinct distances measured for ``call``, large enough to act on."""
    values = {round(v, 3) for key, v in call.measured.items() if key in DISTANCES and v >= MIN_DISTANCE}
    return sorted(values)


def _direction(task: Task, program: Program, k: int) -> np.ndarray | None:
    """Unit x-y direction in which motion ``k`` moves its object (from the object's planned start to its target)."""
    move = program.motions[k]
    assert move.point is not None and move.obj is not None
    refs = {ref for ref, _ in move.point.axes}
    if len(refs) == 1 and (ref := next(iter(refs))) is not None and ref.obj == move.obj:
        delta = np.array([offset for _, offset in move.point.axes[:2]])  # aimed relative to the object itself
    else:
        delta = move.point.estimate()[:2] - np.asarray(task.object(move.obj).center[:2])
    norm = float(np.linalg.norm(delta))
    if norm < 1e-6:
        return None
    return np.array([*(delta / norm), 0.0])
