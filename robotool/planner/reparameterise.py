"""Planner repair: failed programs re-parameterised from what the simulator measured.

When no program succeeded in every world, the best failures are looked at in their first failed world:
the first motion call that measured a distance worth acting on (see :data:`~robotool.rollout.DISTANCES`: a
gap still too wide at a refusal, how far short a motion stopped, how far outside the workspace a target
was, how far a grasp was from what it should hold), or else the first that did not end ``done``. Each
earlier motion that moved an object (a skill acting on an object, such as a push, or a motion whose plan step
involves two objects, such as a held tool dragging another), and then that motion itself when it moved an object
(a push that stopped short of its target), is tried again aimed further along its own direction, and less far, by
each of those distances plus a margin; the simulator decides which variant, if any, works. Nothing here names a
task or an object kind.
"""

from __future__ import annotations

import numpy as np

from robotool import robots
from robotool.planner.codegen import Program
from robotool.rollout import SkillCall, notable_distances
from robotool.solution import Candidate
from robotool.task.task_model import Task

MARGIN = 0.03  # m added to a measured distance when a target is moved by it
MOVERS = 2  # object-moving motions before the failure that are re-parameterised (latest first), then the failing one


def repaired(task: Task, program: Program, candidate: Candidate) -> list[Program]:
    """Variants of ``program`` re-parameterised from ``candidate``'s first failed world (none without evidence)."""
    failed = next((r for r in candidate.rollouts if not r.success), None)
    if failed is None or failed.error is not None:
        return []
    kinds = {s.name: s.kind for s in robots.get(task.embodiment).skills}
    motions = [c for c in failed.calls if kinds.get(c.skill) == "motion"]
    failing = next((k for k, c in enumerate(motions) if _distances(c)), None)
    if failing is None:
        failing = next((k for k, c in enumerate(motions) if c.outcome != "done"), len(motions) - 1)
    if failing < 0:
        return []
    distances = _distances(motions[failing])
    up_to_failure = program.motions[: failing + 1]
    movers = [k for k, m in enumerate(up_to_failure) if m.point is not None and _moves_object(program, k)]
    earlier = [k for k in movers if k < failing][-MOVERS:]
    variants = []
    for k in [*reversed(earlier), *(k for k in movers if k == failing)]:
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
                variants.append(program.with_target_shifted(k, shift.tolist(), why))
    return variants


def _distances(call: SkillCall) -> list[float]:
    """The distinct distances measured for ``call``, large enough to act on."""
    return sorted({round(v, 3) for v in notable_distances(call.measured).values()})


def _moves_object(program: Program, k: int) -> bool:
    """Whether motion ``k`` acts on an object, or its plan step involves two objects (one held, one moved)."""
    move = program.motions[k]
    return move.obj is not None or len(program.steps[move.step - 1].objects) >= 2


def _direction(task: Task, program: Program, k: int) -> np.ndarray | None:
    """Unit x-y direction of motion ``k``: from its object's planned start to the target for a skill acting on
    an object, else from the previous motion's target."""
    move = program.motions[k]
    assert move.point is not None
    refs = {ref for ref, _ in move.point.axes}
    if move.obj is not None and len(refs) == 1 and (ref := next(iter(refs))) is not None and ref.obj == move.obj:
        delta = np.array([offset for _, offset in move.point.axes[:2]])  # aimed relative to the object itself
    elif move.obj is not None:
        delta = move.point.estimate()[:2] - np.asarray(task.object(move.obj).center[:2])
    else:
        before = next((m.point for m in reversed(program.motions[:k]) if m.point is not None), None)
        if before is None:
            return None
        delta = move.point.estimate()[:2] - before.estimate()[:2]
    norm = float(np.linalg.norm(delta))
    if norm < 1e-6:
        return None
    return np.array([*(delta / norm), 0.0])
