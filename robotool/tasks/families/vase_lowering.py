"""vase_lowering: bring a fragile vase down from a sofa without breaking it.

Description:
    A glass vase (breaks after a fall of more than 0.3 m onto a hard surface) lies on a sofa; the
    quadruped starts on the floor and must get the vase's bottom down to the goal height. Fixed boxes of
    0.12 m and 0.24 m stand against the sofa as steps. For a sofa higher than the vase can fall, the robot
    pushes the soft cushion beside the sofa, climbs the steps and pushes the vase off onto the cushion.
Randomizations:
    - the sofa's height: 0.08-0.12 m (no tool: climb on and push the vase to the floor), 0.16-0.24 m
      (climb the steps; the fall is safe) or 0.31-0.36 m (steps and cushion); the goal height is 0.20 m
      when the vase must land on the 0.16 m cushion and 0.05 m otherwise;
    - the steps' place along the sofa, the vase's place on it, the cushion's place on the floor;
    - decoys: a sand-filled cushion too heavy to push; in unsolvable scenes the first step is a fixed box
      too tall to climb (0.28-0.32 m), so the sofa cannot be reached; a scene that needs the steps is also
      unsolvable when the vase lies where they lead onto the sofa, so near its edge that the robot cannot stop
      there with every foot on the sofa and its body clear of the vase, its length along the climb or across it
      (it may turn a quarter on the floor first), unless the sofa's top is level with the top step's (within the
      push's 0.04 m): then the robot, on the step, pushes the vase out of its way;
    - 0-3 fixed pieces of furniture away from the scene; the whole scene mirrored, turned by quarter
      turns and shifted on the floor.
Success conditions:
    - the vase's bottom is at most the goal height above the ground at the end, and the vase is unbroken.
"""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.task.scene import SceneObject
from robotool.tasks.families._common import (
    CLEARANCE,
    FLOOR_CLUTTER,
    Draft,
    draw_layout,
    draw_variant,
    footprint,
    free_spot,
    grow,
    hull,
    on_top,
    scatter,
    spot_for,
    template,
    uniform,
)

MAX_DROP = 0.3
CUSHION = (0.5, 0.5, 0.16)
STEP = (0.4, 0.6)
SIDE_MARGIN = QUADRUPED.side_margin  # m its body keeps from what it must not touch
SAME_LEVEL = QUADRUPED.rise  # m: a step top no higher than this above the sofa's does not meet the body
PUSH_LEVEL = QUADRUPED.same_surface  # m: a robot on the step pushes what rests on a sofa top no farther than this
# from the step's (the push rules' same surface)


def build(rng: np.random.Generator) -> Draft:
    """One vase_lowering scene from the random stream."""
    variant = draw_variant(rng)
    layout = draw_layout(rng, arm=False)
    cushioned = variant == "unsolvable" or (variant == "tool" and rng.random() < 0.7)
    height = (
        uniform(rng, 0.08, 0.12)
        if variant == "no_tool"
        else uniform(rng, 0.31, 0.36)
        if cushioned
        else uniform(rng, 0.16, 0.24)
    )
    steps_y = uniform(rng, -0.25, 0.65)
    first_step = uniform(rng, 0.28, 0.32) if variant == "unsolvable" else 0.12
    scene = [
        on_top("sofa", "box", (3.0, 0.2), (0.9, 1.5, height), movable=False, notes="a sofa"),
        on_top(
            "box_1",
            "box",
            (1.95 - 2 * CLEARANCE, steps_y),
            (*STEP, first_step),
            movable=False,
            notes="a box fixed in place",
        ),
        on_top(
            "box_2",
            "box",
            (2.35 - CLEARANCE, steps_y),
            (*STEP, 0.24),
            movable=False,
            notes="a box fixed in place against the sofa",
        ),
        on_top(
            "glass_vase",
            "box",
            (uniform(rng, 2.8, 3.2), uniform(rng, 0.6, 0.85)),
            (0.3, 0.1, 0.1),
            height,
            mass=0.5,
            fragile={"max_drop": MAX_DROP},
            notes="a glass vase lying on the sofa",
        ),
    ]
    start = (0.0, uniform(rng, -0.4, 0.4))
    body = (start[0] - 0.33, start[1] - 0.15, start[0] + 0.33, start[1] + 0.15)
    floor = (0.5, -1.0, 1.5, 1.2)
    spot = spot_for(rng, CUSHION[:2], floor, [footprint(o) for o in scene] + [body], 0.2)
    scene.append(on_top("soft_cushion", "box", spot, CUSHION, mass=1.0, soft=True, notes="a soft cushion"))
    decoys = ["box_1"] if variant == "unsolvable" else []
    free = free_spot(rng, CUSHION[:2], floor, [footprint(o) for o in scene] + [body], 0.2)
    if variant == "tool" and cushioned and free is not None and rng.random() < 0.4:
        scene.append(
            on_top(
                "sand_cushion",
                "box",
                free,
                CUSHION,
                mass=uniform(rng, 7.0, 9.0, 1),
                soft=True,
                notes="a floor cushion filled with sand",
            )
        )
        decoys.append("sand_cushion")
    area = hull([footprint(o) for o in scene] + [body])
    scene += scatter(
        rng,
        scene,
        int(rng.integers(0, 4)),
        FLOOR_CLUTTER,
        grow(area, 2.0),
        [grow(area, 0.5)],
        movable=False,
        margin=0.1,
    )
    goal_height = 0.20 if height > MAX_DROP else 0.05
    blocked = variant == "tool" and not room_to_land(scene[0], scene[2], scene[3])
    if blocked:
        variant, decoys = "unsolvable", [*decoys, "box_1", "box_2"]
    tools = {
        "no_tool": [],
        "unsolvable": [],
        "tool": ["soft_cushion", "box_1", "box_2"] if cushioned else ["box_1", "box_2"],
    }[variant]
    return Draft(
        variant=variant,
        category="sequential_tool_use",
        instruction="Put the glass vase down on the ground without breaking it.",
        robot={"type": "quadruped", "position": list(layout.point(start))},
        objects=[layout.place(o) for o in scene],
        goal={"lowered": {"object": "glass_vase", "height": goal_height}},
        tools=tools,
        decoys=decoys,
        layout=layout,
        varied=f"sofa {height:.2f} m high, goal height {goal_height:.2f} m; "
        + ("the vase lies where the steps lead onto the sofa; " if blocked else "")
        + f"{'decoys: ' + ', '.join(decoys) if decoys else 'no decoys'}",
    )


def room_to_land(sofa: SceneObject, step: SceneObject, vase: SceneObject) -> bool:
    """Whether the robot, climbing from ``step`` onto ``sofa`` (along the template's +x, before the layout places the
    scene), can stop on the sofa with every foot on it and its body clear of ``vase`` and of a higher step behind it,
    or, on a sofa level with the step, push the vase out of its way from the step first.

    The robot may turn a quarter in place on the floor before it climbs, so its body may lie along the climb or
    across it, however the scene is turned; it stops as near the sofa's edge as it can, on the line across the
    step farthest from the vase."""
    if abs(step.top - sofa.top) <= PUSH_LEVEL:
        return True
    limits = template("vase_lowering").limits
    assert isinstance(limits, QuadrupedLimits)  # the family's template is a quadruped task
    size = np.asarray(limits.body_size[:2])
    return any(_lands(half, sofa, step, vase) for half in (size / 2, size[::-1] / 2))


def _lands(half: np.ndarray, sofa: SceneObject, step: SceneObject, vase: SceneObject) -> bool:
    """:func:`room_to_land` for a body of x-y half size ``half`` (along the climb, across it)."""
    feet = half - QUADRUPED.foot_radius  # the feet's centres sit a foot's radius inside the body's outline
    s, t, v = footprint(sofa), footprint(step), footprint(vase)
    behind = half[0] + SIDE_MARGIN if step.top > sofa.top + SAME_LEVEL else feet[0]
    if float(s[0] + behind + half[0] + SIDE_MARGIN) <= v[0]:
        return True
    lo, hi = max(t[1], s[1]) + feet[1], min(t[3], s[3]) - feet[1]  # lines with every foot over the step and the sofa
    return bool(lo <= hi and (lo + half[1] + SIDE_MARGIN <= v[1] or hi - half[1] - SIDE_MARGIN >= v[3]))
