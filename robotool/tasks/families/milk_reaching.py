"""milk_reaching: grasp a milk carton that may stand beyond the arm's reach.

Description:
    The arm (base at the origin, workspace x in [-0.30, 0.45], y in [-0.45, 0.45]) must hold the milk
    carton. A hammer (an L-shaped hook) lies on the table with its handle inside the workspace; when the
    carton stands beyond x = 0.45 the arm grasps the handle, reaches the head behind the carton and pulls
    it in. A stuffed toy and a padlock stand near the carton as in the paper.
Randomizations:
    - the carton's position: inside the workspace (no tool) or 0.09-0.19 m beyond its +x edge; an unsolvable
      carton stands beyond the reach of everything the arm can hold (each movable object held at its near end at
      the workspace edge), since anything that touches it can do more than hook it (a straight stick pressed on
      its top and dragged back tips it over toward the arm);
    - the hammer's length (0.38-0.44 m, always long enough to reach behind a far carton) and place;
    - decoys: a straight stick (it has no head to pull with) and, when no hammer is given, a small hammer
      whose head cannot get behind the carton; the toy and the lock move by up to 2 cm;
    - 0-2 light table-top distractors away from the hammer's sweep; the layout mirrored in y (the
      hook is turned over, roll 180 deg, so its head points along -y and still reaches behind the carton).
Success conditions:
    - the gripper holds the milk at the end.
"""

from __future__ import annotations

import numpy as np

from robotool.robots.arm.arm_skills import ArmLimits
from robotool.task.scene import SceneObject
from robotool.tasks.families._common import (
    ARM_CLUTTER,
    Draft,
    draw_layout,
    draw_variant,
    footprint,
    on_top,
    scatter,
    uniform,
)

ARM_REACH_X = ArmLimits().workspace_max[0]  # the workspace's +x edge
HOOK_HEAD = 0.20  # length of the hammer's head along y
HOOK_GRIP = 0.10  # graspable point: this far from the handle's -x end
MILK = (0.044, 0.044, 0.16)
MARGIN = 0.03  # how far behind the carton the head must get
FAR_MILK_X = (0.54, 0.64)  # where a carton out of reach stands (an unsolvable one: as far beyond its bound)
MILK_GRASP_HEIGHT = 0.135  # the carton's graspable point above its bottom


def out_of_reach_x(objects: list[SceneObject]) -> float:
    """Nearest x of a carton that none of the movable ``objects`` reaches: the longest along x, held at its near
    end with the gripper at the workspace edge, stops ``MARGIN`` short of the carton's near face."""
    longest = max(right - left for left, _, right, _ in (footprint(o) for o in objects if o.movable))
    return round(ARM_REACH_X + longest + MARGIN + MILK[0] / 2, 4)


def carton(xy: tuple[float, float]) -> SceneObject:
    """The milk carton standing at ``xy``."""
    return on_top(
        "milk", "box", xy, MILK, mass=0.25, graspable_point=(*xy, MILK_GRASP_HEIGHT), notes="a carton of milk"
    )


def hook(name: str, length: float, xy: tuple[float, float], notes: str) -> SceneObject:
    """A flat L-shaped hook whose handle's -x end is at ``xy`` (handle centre line y)."""
    x0, y = xy
    return on_top(
        name,
        "hook",
        (x0 + length / 2, y - 0.01 + HOOK_HEAD / 2),
        (length, HOOK_HEAD, 0.03),
        mass=0.4,
        graspable_point=(x0 + HOOK_GRIP, y, 0.03),
        notes=notes,
    )


def stick(name: str, length: float, xy: tuple[float, float], notes: str) -> SceneObject:
    """A straight stick along x whose -x end is at ``xy``, held 0.1 m from that end."""
    x0, y = xy
    return on_top(
        name,
        "box",
        (x0 + length / 2, y),
        (length, 0.02, 0.03),
        mass=0.15,
        graspable_point=(x0 + HOOK_GRIP, y, 0.03),
        notes=notes,
    )


def build(rng: np.random.Generator) -> Draft:
    """One milk_reaching scene from the random stream."""
    variant = draw_variant(rng)
    layout = draw_layout(rng, arm=True)
    hook_notes = "a hammer lying flat, shaped like an L: a handle and a head at one end of it"
    if variant == "no_tool":
        milk_xy = (uniform(rng, 0.25, 0.42), uniform(rng, 0.12, 0.30))
    else:
        milk_xy = (uniform(rng, *FAR_MILK_X), uniform(rng, 0.02, 0.14))  # clear of the toy's row
    length = uniform(rng, 0.38, 0.44)
    handle = (uniform(rng, -0.20, -0.12), uniform(rng, -0.36, -0.30))
    tools: list[SceneObject] = []
    decoys: list[str] = []
    if variant == "unsolvable":
        tools.append(hook("small_hammer", uniform(rng, 0.16, 0.20), handle, hook_notes))
        decoys.append("small_hammer")
    else:
        tools.append(hook("hammer", length, handle, hook_notes))
    if variant == "unsolvable" or rng.random() < 0.5:
        tools.append(
            stick("stick", uniform(rng, 0.30, 0.40), (-0.25, uniform(rng, 0.34, 0.40)), "a thin straight stick")
        )
        decoys.append("stick")
    milk = carton(milk_xy)
    scene = [
        milk,
        on_top(
            "stuffed_toy",
            "box",
            (uniform(rng, 0.43, 0.47), uniform(rng, -0.07, -0.03)),
            (0.08, 0.05, 0.05),
            mass=0.1,
            notes="a small soft toy",
        ),
        on_top(
            "lock",
            "box",
            (uniform(rng, 0.33, 0.37), uniform(rng, 0.03, 0.07)),
            (0.04, 0.03, 0.02),
            mass=0.05,
            notes="a small padlock",
        ),
        *tools,
    ]
    sweep = (-0.25, handle[1] - 0.05, 0.80, max(milk_xy[1] + 0.08, handle[1] + HOOK_HEAD + 0.05))
    base = (-0.15, -0.15, 0.15, 0.15)
    scene += scatter(
        rng,
        scene,
        int(rng.integers(0, 3)),
        ARM_CLUTTER,
        (-0.28, -0.44, 0.42, 0.44),
        [sweep, base, footprint(milk)],
        movable=True,
        margin=0.04,
    )
    if variant == "unsolvable":  # as far beyond the reach of everything else as a far carton is beyond 0.54 m
        milk_xy = (round(milk_xy[0] - FAR_MILK_X[0] + out_of_reach_x(scene[1:]), 4), milk_xy[1])
        scene[0] = carton(milk_xy)
    outside = milk_xy[0] - ARM_REACH_X
    where = f"{outside:.2f} m beyond the workspace" if outside > 0 else "inside the workspace"
    needed = {"no_tool": [], "tool": ["hammer"], "unsolvable": []}[variant]
    return Draft(
        variant=variant,
        category="tool_selection",
        instruction="Grasp the milk carton.",
        robot={"type": "arm"},
        objects=[layout.place(o) for o in scene],
        goal={"grasped": "milk"},
        tools=needed,
        decoys=decoys,
        layout=layout,
        varied=f"milk at x = {milk_xy[0]:.2f} m ({where}); {'decoys: ' + ', '.join(decoys) if decoys else 'no decoys'}",
    )
