"""The arm's candidate programs for the LM-free planner: every program the macros (:mod:`.arm_macros`) make for a
task, unordered (the search orders them)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from robotool.planner.codegen import Program
from robotool.planner.layout import Box
from robotool.robots.arm.arm_macros import (
    Arm,
    chain,
    drag_support,
    finish,
    hook_laterals,
    hook_pull,
    pick,
    press_direct,
    press_face,
    press_with,
    tool_push,
)
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task


def candidates(task: Task, tools: bool) -> Iterator[Program]:
    """Every program the macros make for the task (unordered; the search orders them)."""
    arm = Arm(task)
    target = task.object(task.goal.object)
    if task.goal.kind == "pressed":
        yield from _press_programs(arm, target, tools)
        return
    direct = Program()
    finish(direct, arm, target)
    direct.say(f"Grasp {target.name} directly.")
    yield direct
    if not tools:
        return
    tool_objects = [o for o in task.objects if o is not target and arm.graspable(o)]
    for hook in (o for o in tool_objects if o.shape == "hook"):
        for lateral in hook_laterals(arm, hook, target):
            prog = Program()
            if hook_pull(prog, arm, hook, target, lateral):
                _finish(prog, arm, target)
                yield prog
    for support in (o for o in tool_objects if _rests_on(target, o)):
        prog = Program()
        if drag_support(prog, arm, support, target, Box.of(target).center):
            _finish(prog, arm, target)
            yield prog
    for support in tool_objects:
        if support.top > 0.01 or _rests_on(target, support):
            continue
        for dest in _onto(Box.of(target), Box.of(support)):
            for tool in tool_objects:
                if tool is support:
                    continue
                prog = Program()
                if tool_push(prog, arm, tool, target, dest) and drag_support(prog, arm, support, target, dest):
                    _finish(prog, arm, target)
                    yield prog


def _finish(prog: Program, arm: Arm, target: SceneObject) -> None:
    finish(prog, arm, target)
    prog.say(f"Then grasp {target.name}.")


def _rests_on(obj: SceneObject, support: SceneObject) -> bool:
    """Whether ``obj`` stands on ``support`` (its bottom at the support's top, footprints overlapping)."""
    return abs(obj.bottom - support.top) < 0.01 and Box.of(obj).overlap(Box.of(support)) > 0.01


def _onto(box: Box, sheet: Box) -> list[np.ndarray]:
    """Places for ``box`` on ``sheet``: the nearest one well inside it, and the one on its centre line."""
    margin = box.half + 0.03
    lo, hi = sheet.lo + margin, sheet.hi - margin
    if np.any(lo > hi):
        return []
    nearest = np.clip(box.center, lo, hi)
    axis = int(np.argmax(np.abs(nearest - box.center)))
    line = nearest.copy()
    line[axis] = sheet.center[axis]
    out = [nearest]
    if np.linalg.norm(line - nearest) > 0.02:
        out.append(line)
    return out


def _press_programs(arm: Arm, button: SceneObject, tools: bool) -> Iterator[Program]:
    for drop in (0.0, 0.035):
        prog = Program()
        press_direct(prog, arm, button, drop)
        yield prog
    if not tools:
        return
    _, n = press_face(button)
    movable = [o for o in arm.task.objects if o is not button and arm.graspable(o)]
    for tool in movable:
        prog = Program()
        g = pick(prog, tool, f"tool: a rigid object to press {button.name} with")
        if press_with(prog, arm, button, tool, [tool], g):
            yield prog
    magnets = sorted(
        (o for o in arm.task.objects if o.magnetic and o.movable), key=lambda o: float(np.asarray(o.center[:2]) @ n)
    )
    for holder in (m for m in magnets if arm.graspable(m)):
        rest = [m for m in magnets if m is not holder]
        for count in range(1, len(rest) + 1):
            prog = Program()
            chained = chain(prog, arm, holder, rest[:count], n)
            if chained is not None and press_with(prog, arm, button, holder, [holder, *rest[:count]], chained):
                yield prog
