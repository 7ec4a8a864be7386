"""Arm macros: pick, finish the goal, press, pull with a hook, push with a held object, drag a support,
chain magnetic objects. Each macro appends skill calls to a :class:`Program`; :func:`candidates` combines
them into programs for a task, with parameters from the scene's geometry and the arm's workspace.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.planner.codegen import Point, Program, Ref
from robotool.planner.layout import Box
from robotool.robots.arm.arm_config import ARM
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.task import geometry
from robotool.task.concepts import press_point
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task

# the macros' tunables, documented in ArmConfig
CLEAR = ARM.approach_height
SLIDE = ARM.slide_lift
GAP = ARM.tool_gap
HOOK_LATERALS = (0.0, 0.5, 0.25, 0.75)  # where the target may sit along a hook's head, 0 nearest its handle
INSIDE = ARM.inside_margin
CARRY = ARM.carry_clearance
PRESS = ARM.press_depth
STOW = ARM.stow_back
ATTACH = ARM.attach_depth


class Arm:
    """The arm's view of one task: its workspace and the objects' boxes."""

    def __init__(self, task: Task):
        self.task = task
        limits = task.limits
        assert isinstance(limits, ArmLimits)
        self.lo, self.hi = np.asarray(limits.workspace_min), np.asarray(limits.workspace_max)
        self.opening = limits.gripper_opening

    def inside(self, point: np.ndarray, margin: float = 0.0) -> bool:
        """Whether an x-y(-z) point lies in the workspace, ``margin`` inside its walls."""
        k = len(point)
        return bool(np.all(point >= self.lo[:k] + margin - 1e-9) and np.all(point <= self.hi[:k] - margin + 1e-9))

    def grasp_offset(self, obj: SceneObject) -> np.ndarray:
        """From an object's graspable point to its centre."""
        return np.asarray(obj.center) - np.asarray(obj.grasp_point)

    def carry_height(self, held: list[SceneObject], holder: SceneObject) -> float:
        """Gripper height at which the held objects clear every other object's top."""
        others = [o.top for o in self.task.objects if o not in held]
        below = holder.grasp_point[2] - min(o.bottom for o in held)
        return float(min(max(others, default=0.0) + CARRY + below, self.hi[2]))

    def graspable(self, obj: SceneObject) -> bool:
        """Whether the fingers can hold ``obj`` at its graspable point: movable, in the workspace, and no wider
        there across the fingers (along y, the way they close) than their opening; a sheet is pinched."""
        return (
            obj.movable
            and obj.shape not in ("cloth", "button")
            and self.inside(np.asarray(obj.grasp_point))
            and (obj.is_sheet or _width_across_fingers(obj) <= self.opening)
        )

    def bring_in(self, grasp_xy: np.ndarray) -> np.ndarray:
        """Where an out-of-reach graspable point (x-y) should be moved to: just inside the workspace."""
        return np.clip(grasp_xy, self.lo[:2] + INSIDE, self.hi[:2] - INSIDE)


def _width_across_fingers(obj: SceneObject) -> float:
    """The width along y (the fingers' closing axis) of the narrowest of ``obj``'s parts under its graspable point
    (the whole object's when none is under it), as it lies."""
    parts = geometry.object_parts(obj)
    point = np.asarray(obj.grasp_point[:2], dtype=float)[None, :]
    under = [p for p in parts if not np.isnan(p.vertical_interval(point)[1][0])] or parts
    return min(float(hi[1] - lo[1]) for lo, hi in (p.aabb() for p in under))


# --- macros ------------------------------------------------------------------------------------------


def pick_and_lift(
    prog: Program, arm: Arm, tool: SceneObject, target: SceneObject, role: str
) -> tuple[Ref, float, float]:
    """Grasp ``tool``, query ``target``'s centre and lift the tool above everything.

    Returns the target's centre, the carrying height and the height to slide the tool at.
    """
    g = pick(prog, tool, role)
    t = prog.query("get_center", target.name, target.center)
    carry = arm.carry_height([tool], tool)
    prog.motion(
        "move_to_position",
        point=Point.at(g).with_axis(2, None, carry),
        objects=[tool.name],
        intent=f"lift {tool.name} above everything",
    )
    return t, carry, tool.grasp_point[2] + SLIDE


def pick(prog: Program, obj: SceneObject, role: str) -> Ref:
    """Open, approach the graspable point from above, close on it. Returns the queried point."""
    prog.use(obj.name, role)
    g = prog.query("get_graspable_point", obj.name, obj.grasp_point)
    prog.motion("open_gripper", intent="open the gripper")
    prog.motion(
        "move_to_position",
        point=Point.at(g, (0, 0, CLEAR)),
        objects=[obj.name],
        intent=f"move above {obj.name}'s graspable point",
        explanation=f"{CLEAR} m above it",
    )
    prog.motion(
        "move_to_position",
        point=Point.at(g),
        objects=[obj.name],
        intent=f"lower the gripper onto {obj.name}'s graspable point",
    )
    prog.motion("close_gripper", objects=[obj.name], intent=f"grasp {obj.name}")
    return g


def release(prog: Program, at: Point, obj: str) -> None:
    """Open the gripper and move up clear of what it held."""
    prog.motion("open_gripper", objects=[obj], intent=f"release {obj}")
    prog.motion(
        "move_to_position",
        point=at.shifted((0, 0, CLEAR)),
        intent=f"move up away from {obj}",
        explanation=f"{CLEAR} m above where {obj} was released",
    )


def finish(prog: Program, arm: Arm, target: SceneObject) -> None:
    """Grasp the goal object (now within reach) and do what the goal asks with it."""
    goal = arm.task.goal
    g = pick(prog, target, "target")
    if goal.kind == "lowered":
        place_lower(prog, arm, target, g)
        return
    rise = 0.05 if goal.kind == "grasped" else goal.lifted.height + 0.03  # type: ignore[union-attr]
    top = min(target.grasp_point[2] + rise, arm.hi[2])
    prog.motion(
        "move_to_position",
        point=Point.at(g).with_axis(2, None, top),
        objects=[target.name],
        intent=f"lift {target.name}",
        explanation=f"{rise:.2f} m above where it was grasped",
    )


def place_lower(prog: Program, arm: Arm, target: SceneObject, g: Ref) -> None:
    """Carry the held object to the free table spot nearest to it and set it down there."""
    box = Box.of(target)
    spot = free_table_spot(arm, box)
    carry = arm.carry_height([target], target)
    lift = target.grasp_point[2] - target.bottom + 0.005
    dx, dy = spot - box.center
    prog.motion(
        "move_to_position",
        point=Point.at(g).with_axis(2, None, carry),
        objects=[target.name],
        intent=f"lift {target.name} clear of everything",
    )
    over = Point.at(g, (dx, dy, 0)).with_axis(2, None, carry)
    prog.motion("move_to_position", point=over, objects=[target.name], intent="carry it over a free spot on the table")
    down = over.with_axis(2, None, lift)
    prog.motion("move_to_position", point=down, objects=[target.name], intent=f"set {target.name} on the table")
    release(prog, down, target.name)


def free_table_spot(arm: Arm, box: Box) -> np.ndarray:
    """The x-y spot nearest to ``box`` where it stands on the table inside the workspace, touching nothing."""
    others = [Box.of(o) for o in arm.task.objects if o.name != box.name]
    best, best_d = box.center, np.inf
    for x in np.arange(arm.lo[0] + box.half[0], arm.hi[0] - box.half[0], 0.02):
        for y in np.arange(arm.lo[1] + box.half[1], arm.hi[1] - box.half[1], 0.02):
            spot = np.array([x, y])
            d = float(np.linalg.norm(spot - box.center))
            moved = box.moved_to(spot)
            if d < best_d and all(moved.overlap(o) < -0.02 for o in others):
                best, best_d = spot, d
    return best


@dataclass(frozen=True)
class HookWay:
    """Where a hook pull goes: the gripper's x-y offset from the target's centre where the head is lowered (``pre``),
    the pull's direction and length, the target's offset along the head (``lateral``), and how far from every other
    object the hook lands (``clearance``, m; below 0 where it lands on one)."""

    pre: np.ndarray
    pull: np.ndarray
    pull_by: float
    lateral: float
    clearance: float


def hook_way(arm: Arm, hook: SceneObject, target: SceneObject, lateral: float) -> HookWay | None:
    """The pull with the target ``lateral`` of the way along the head from the handle (0: as near it as fits, 1: as
    far), or None when the head cannot reach behind the target or the pull leaves the workspace."""
    handle, head = geometry.object_parts(hook)
    axis = _flat(handle.rot[:, 0])
    reach = axis * np.sign((head.center - handle.center)[:2] @ axis)  # from the handle to the head
    pull = -reach
    goal_xy = arm.bring_in(np.asarray(target.grasp_point[:2]))
    want = goal_xy - np.asarray(target.grasp_point[:2])
    if np.linalg.norm(want) < 1e-6 or _flat(want) @ pull < 0.7:
        return None
    side = _flat((head.center - handle.center)[:2] - ((head.center - handle.center)[:2] @ axis) * axis)
    g0 = np.asarray(hook.grasp_point)
    face = head.center[:2] + pull * hook.thickness / 2  # the head's inner face, which meets the target
    face_along = (face - g0[:2]) @ pull
    handle_side = (handle.center[:2] - g0[:2]) @ side
    head_far = (head.center[:2] - g0[:2]) @ side + hook.size[1] / 2
    box = Box.of(target)
    t_along, t_side = float(np.abs(pull) @ box.half), float(np.abs(side) @ box.half)
    near = handle_side + hook.thickness / 2 + t_side + 0.01
    far = head_far - t_side - 0.005
    if near > far:
        return None
    s = near + lateral * (far - near)
    pull_by = float(want @ pull) + GAP
    pre = -pull * (t_along + GAP + face_along) - side * s
    g_pre = box.center + pre
    if not (arm.inside(g_pre) and arm.inside(g_pre + pull * pull_by)):
        return None
    return HookWay(pre, pull, pull_by, float(s), _landing_clearance(arm, hook, target, g_pre - g0[:2]))


def _landing_clearance(arm: Arm, hook: SceneObject, target: SceneObject, shift: np.ndarray) -> float:
    """How far ``hook``, lowered where it is moved by ``shift`` (x-y), lands from every object but ``target`` that
    stands higher than it slides (m, below 0 where it lands on one): lowered onto one and dragged, it would press on it
    with the arm's full force."""
    boxes = [Box.of(o) for o in arm.task.objects if o is not hook and o is not target]
    clearance = np.inf
    for part in geometry.object_parts(hook):
        lo, hi = (b[:2] + shift for b in part.aabb())
        landing = Box(hook.name, lo, hi, 0.0, 0.0)
        clearance = min([clearance, *(-landing.overlap(box) for box in boxes if box.top > SLIDE)])
    return float(clearance)


def hook_laterals(arm: Arm, hook: SceneObject, target: SceneObject) -> list[float]:
    """The two places along the head (``HOOK_LATERALS``) where the hook lands furthest from the other objects, the
    clearest first (ties in the order of ``HOOK_LATERALS``)."""
    ways = [
        (way.clearance, -k, lateral)
        for k, lateral in enumerate(HOOK_LATERALS)
        if (way := hook_way(arm, hook, target, lateral))
    ]
    return [lateral for _, _, lateral in sorted(ways, reverse=True)[:2]]


def hook_pull(prog: Program, arm: Arm, hook: SceneObject, target: SceneObject, lateral: float) -> bool:
    """Reach the hook's head behind the target and pull it into the workspace. False if it cannot."""
    way = hook_way(arm, hook, target, lateral)
    if way is None:
        return False
    pre, pull, pull_by, s = way.pre, way.pull, way.pull_by, way.lateral
    t, carry, low = pick_and_lift(
        prog, arm, hook, target, f"tool: a hook whose head reaches behind {target.name} to pull it in"
    )
    above = Point.at(t, (*pre, 0)).with_axis(2, None, carry)
    prog.motion(
        "move_to_position",
        point=above,
        objects=[hook.name, target.name],
        intent=f"carry {hook.name}'s head over the far side of {target.name}",
        explanation=f"head's inner face {GAP} m beyond {target.name}, {target.name} {s:.3f} m along the head",
    )
    down = above.with_axis(2, None, low)
    prog.motion("move_to_position", point=down, objects=[hook.name], intent=f"lower {hook.name}'s head to the table")
    end = down.shifted((*(pull * pull_by), 0))
    prog.motion(
        "move_to_position",
        point=end,
        objects=[hook.name, target.name],
        intent=f"pull {target.name} into the workspace with {hook.name}",
        explanation=f"{pull_by:.3f} m, until its graspable point is {INSIDE} m inside the workspace",
    )
    release(prog, end, hook.name)
    prog.say(f"Grasp {hook.name}, reach its head behind {target.name} and pull {target.name} into the workspace.")
    return True


def tool_push(prog: Program, arm: Arm, tool: SceneObject, target: SceneObject, dest: np.ndarray) -> bool:
    """Grasp ``tool``, push ``target`` with it until the target's centre is at ``dest`` (x-y), set it aside."""
    box = Box.of(target)
    delta = dest - box.center
    dist = float(np.linalg.norm(delta))
    if dist < 0.01:
        return False
    d = delta / dist
    side = np.array([-d[1], d[0]])
    g0 = np.asarray(tool.grasp_point)
    corners = np.vstack([p.corners() for p in geometry.object_parts(tool)])[:, :2] - g0[:2]
    face = float(np.max(corners @ d))
    span = corners @ side
    t_along, t_side = float(np.abs(d) @ box.half), float(np.abs(side) @ box.half)
    q_lo, q_hi = span.min() + t_side, span.max() - t_side  # target's lateral offset from the gripper
    if q_lo > q_hi:
        return False
    back = -d * (t_along + GAP + face)
    options = sorted(np.linspace(q_lo, q_hi, 9), key=lambda q: abs(q - (box.center - g0[:2]) @ side))
    q = next(
        (
            q
            for q in options
            if arm.inside(box.center + back - side * q) and arm.inside(box.center + back - side * q + d * (dist + GAP))
        ),
        None,
    )
    if q is None:
        return False
    t, carry, low = pick_and_lift(prog, arm, tool, target, f"tool: a rigid object to push {target.name} with")
    above = Point.at(t, (*(back - side * q), 0)).with_axis(2, None, carry)
    prog.motion(
        "move_to_position",
        point=above,
        objects=[tool.name],
        intent=f"carry {tool.name} behind {target.name}",
        explanation=f"its face {GAP} m behind {target.name}",
    )
    down = above.with_axis(2, None, low)
    prog.motion("move_to_position", point=down, objects=[tool.name], intent=f"lower {tool.name} to the table")
    end = down.shifted((*(d * (dist + GAP)), 0))
    prog.motion(
        "move_to_position",
        point=end,
        objects=[tool.name, target.name],
        intent=f"push {target.name} with {tool.name}",
        explanation=f"{dist:.3f} m to [{dest[0]:.3f}, {dest[1]:.3f}]",
    )
    prog.motion(
        "move_to_position", point=end.with_axis(2, None, carry), objects=[tool.name], intent=f"lift {tool.name} off"
    )
    stow = down.shifted((*(-d * STOW), 0))
    prog.motion(
        "move_to_position",
        point=stow.with_axis(2, None, carry),
        objects=[tool.name],
        intent=f"carry {tool.name} back out of the way",
    )
    prog.motion("move_to_position", point=stow, objects=[tool.name], intent=f"set {tool.name} down")
    release(prog, stow, tool.name)
    prog.say(f"Push {target.name} with {tool.name} to [{dest[0]:.2f}, {dest[1]:.2f}].")
    return True


def drag_support(prog: Program, arm: Arm, support: SceneObject, target: SceneObject, target_xy: np.ndarray) -> bool:
    """Drag ``support`` (with the target on it, its centre at ``target_xy``) until the target is within reach."""
    grasp_xy = target_xy + (np.asarray(target.grasp_point) - np.asarray(target.center))[:2]
    shift = arm.bring_in(grasp_xy) - grasp_xy
    if np.linalg.norm(shift) < 1e-6 or not arm.inside(np.asarray(support.grasp_point[:2]) + shift):
        return False
    g = pick(prog, support, f"tool: a support that carries {target.name} when dragged")
    end = Point.at(g, (*shift, 0.001))
    prog.motion(
        "move_to_position",
        point=end,
        objects=[support.name, target.name],
        intent=f"drag {support.name} with {target.name} on it into the workspace",
        explanation=f"by [{shift[0]:.3f}, {shift[1]:.3f}] m so {target.name} is {INSIDE} m inside",
    )
    release(prog, end, support.name)
    prog.say(f"Drag {support.name} with {target.name} on it into the workspace.")
    return True


def press_face(button: SceneObject) -> tuple[np.ndarray, np.ndarray]:
    """A button's face centre and the horizontal direction that pushes it in."""
    normal = _flat((geometry.rotation_matrix(button.rpy) @ np.array([1.0, 0.0, 0.0]))[:2])
    return press_point(button), normal


def press_direct(prog: Program, arm: Arm, button: SceneObject, drop: float) -> bool:
    """Push the button's face with the gripper itself, ``drop`` below the face centre."""
    face, n = press_face(button)
    _mind_the_edge(prog, arm, button, face[:2], n)
    prog.use(button.name, "target")
    b = prog.query("get_center", button.name, button.center)
    rel = face - np.asarray(button.center)
    z = max(face[2] - drop, arm.lo[2]) - button.center[2]
    start = Point.at(b, (*(rel[:2] - n * 0.1), z))
    prog.motion("move_to_position", point=start, objects=[button.name], intent=f"move in front of {button.name}'s face")
    prog.motion(
        "move_to_position",
        point=start.shifted((*(n * (0.1 + PRESS)), 0)),
        objects=[button.name],
        intent=f"press {button.name}",
        explanation=f"{PRESS} m past its face",
    )
    prog.say(f"Press {button.name} with the gripper.")
    return True


def press_with(
    prog: Program, arm: Arm, button: SceneObject, holder: SceneObject, held: list[SceneObject], g: Ref
) -> bool:
    """Press the button with the tip of what the gripper holds (``holder`` at the gripper, ``held`` all of it)."""
    face, n = press_face(button)
    tip = tip_reach(holder, held, n)
    press_xy = face[:2] - n * tip + n * PRESS
    if not arm.inside(face[:2] - n * tip + n * 0.012):
        return False
    _mind_the_edge(prog, arm, button, face[:2] - n * tip, n)
    prog.use(button.name, "target")
    b = prog.query("get_center", button.name, button.center)
    rel = face - np.asarray(button.center)
    z = face[2] + holder.grasp_point[2] - holder.center[2]
    carry = max(arm.carry_height(held, holder), z)
    names = [o.name for o in held]
    approach = Point.at(b, (*(press_xy - np.asarray(button.center[:2]) - n * (PRESS + 0.08)), 0))
    prog.motion(
        "move_to_position",
        point=Point.at(g).with_axis(2, None, carry),
        objects=names,
        intent="lift what the gripper holds above everything",
    )
    prog.motion(
        "move_to_position",
        point=approach.with_axis(2, None, carry),
        objects=names,
        intent=f"carry it in front of {button.name}",
    )
    low = approach.with_axis(2, b, z - button.center[2])
    prog.motion(
        "move_to_position",
        point=low,
        objects=names,
        intent=f"lower its tip to the height of {button.name}'s face",
        explanation=f"tip {tip:.3f} m from the gripper, face at [{rel[0]:.3f}, {rel[1]:.3f}] from the centre",
    )
    prog.motion(
        "move_to_position",
        point=low.shifted((*(n * (PRESS + 0.08)), 0)),
        objects=[*names, button.name],
        intent=f"press {button.name} with the tip",
        explanation=f"tip {PRESS} m past the face",
    )
    prog.say(f"Press {button.name} with the far end of {', '.join(names)} held in the gripper.")
    return True


def _mind_the_edge(prog: Program, arm: Arm, button: SceneObject, contact: np.ndarray, n: np.ndarray) -> None:
    """A press whose gripper meets the face at ``contact`` (x-y) and cannot go the whole :data:`PRESS` past it inside
    the workspace (clamped at its edge, it pushes the face in by less, which perturbed worlds undo) is a less likely
    choice: tried after presses that go the whole way, with another tool or more of a chain."""
    deepest = max((t for t in np.linspace(0.0, PRESS, 31) if arm.inside(contact + n * t)), default=0.0)
    if deepest < PRESS - 1e-6:
        prog.late += 1
        prog.thin.append(f"{button.name} pressed {deepest:.3f} m past its face at the workspace edge, not {PRESS}")


def tip_reach(holder: SceneObject, held: list[SceneObject], n: np.ndarray) -> float:
    """How far the held objects reach along ``n`` beyond the gripper (laid end to end from the holder)."""
    g = np.asarray(holder.grasp_point[:2])
    corners = np.vstack([p.corners() for p in geometry.object_parts(holder)])[:, :2]
    reach = float(np.max((corners - g) @ n))
    for obj in held[1:]:
        reach += float(np.abs(n) @ Box.of(obj).half) * 2
    return reach


def chain(prog: Program, arm: Arm, holder: SceneObject, links: list[SceneObject], n: np.ndarray) -> Ref | None:
    """Grasp ``holder`` and attach each of ``links`` to the chain's far end along ``n``. Returns the grasp ref."""
    g0 = np.asarray(holder.grasp_point)
    held = [holder]
    plans = []
    for link in links:
        box = Box.of(link)
        half = float(np.abs(n) @ box.half)
        tip = tip_reach(holder, held, n)
        touch = box.center - n * (half + tip - ATTACH)
        if not arm.inside(touch) or not arm.inside(touch - n * 0.05):
            return None
        plans.append((link, half, tip))
        held.append(link)
    g = pick(prog, holder, "tool part: the magnetic object the gripper holds; the chain grows from it")
    low = g0[2] + SLIDE
    carry = arm.carry_height(held, holder)
    prog.motion(
        "move_to_position",
        point=Point.at(g).with_axis(2, None, carry),
        objects=[holder.name],
        intent=f"lift {holder.name}",
    )
    for link, half, tip in plans:
        prog.use(link.name, "tool part: a magnetic object that sticks to the chain's end")
        c = prog.query("get_center", link.name, link.center)
        before = Point.at(c, (*(-n * (half + tip + 0.05)), 0)).with_axis(2, None, carry)
        prog.motion(
            "move_to_position",
            point=before,
            objects=[holder.name, link.name],
            intent=f"carry the chain behind {link.name}",
        )
        prog.motion(
            "move_to_position",
            point=before.with_axis(2, None, low),
            objects=[holder.name],
            intent="lower the chain to the table",
        )
        contact = before.with_axis(2, None, low).shifted((*(n * (0.05 + ATTACH)), 0))
        prog.motion(
            "move_to_position",
            point=contact,
            objects=[holder.name, link.name],
            intent=f"touch {link.name} with the chain's end so it sticks",
            explanation=f"chain end {tip:.3f} m from the gripper, {ATTACH} m into {link.name}'s near face",
        )
        prog.motion(
            "move_to_position",
            point=contact.with_axis(2, None, carry),
            objects=[holder.name, link.name],
            intent="lift the chain",
        )
    names = ", ".join(o.name for o in held)
    prog.say(f"Chain the magnetic objects {names} into a stick by touching them end to end.")
    return g


def _flat(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v[:2], dtype=float)
    return v / max(float(np.linalg.norm(v)), 1e-12)
