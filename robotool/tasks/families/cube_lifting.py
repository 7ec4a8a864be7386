"""cube_lifting: lift a cube with a lever made of a board lying across a yoga roller.

Description:
    A board rests on a fixed yoga roller (the fulcrum) with its +x end on the floor under a cube and its
    raised -x end propped by a chair. The quadruped, on the floor, cannot push a cube above its 5 kg
    limit; it pushes the chair away, then climbs onto the board's -x end near the fulcrum and walks out
    to the raised end so that its weight tips the lever and lifts the cube. The lever keeps the built-in
    template's geometry exactly.
Randomizations:
    - the cube's mass: 6-11 kg (too heavy to push) or 1.5-5 kg (light enough to push, yet the robot still
      cannot raise it by itself: the lever is needed either way);
    - the chair's place along the board's raised end (its height follows the board; under a light cube, which
      does not hold the board down, pushing the chair out drags the board along, so the chair is light enough that
      both stay under the push limit in every perturbed world), the robot's start
      on the floor on either side of the lever; in scenes turned a quarter the board is wider than the robot
      is long (so that it can walk along the board flank first, without a turn);
    - decoys: a box too heavy to push elsewhere on the floor; in unsolvable scenes the chair is too heavy
      to push away (6-10 kg) or the cube too heavy for the robot's weight on the lever (25-30 kg);
    - 0-3 fixed pieces of furniture away from the lever; the whole scene mirrored, turned by quarter turns
      and shifted on the floor.
    Every instance needs a tool: the quadruped has no skill that raises an object, so the ground truth
    (:mod:`robotool.task.concepts`) marks any ``lifted`` goal as needing one, whatever the cube's mass.
Success conditions:
    - the cube's bottom is at least the goal height (0.10 m) above where it started, at the end.
"""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.task import geometry
from robotool.task.scene import MASS_NOISE
from robotool.tasks.families._common import (
    FLOOR_CLUTTER,
    Draft,
    board_width,
    draw_layout,
    draw_variant,
    footprint,
    free_spot,
    grow,
    hull,
    on_top,
    r4,
    scatter,
    template,
    uniform,
)


def build(rng: np.random.Generator) -> Draft:
    """One cube_lifting scene from the random stream."""
    variant = draw_variant(rng)
    light = variant == "no_tool"  # no lifted goal can be reached without the lever: a light cube instead
    variant = "tool" if light else variant
    layout = draw_layout(rng, arm=False)
    base = template("cube_lifting")
    roller, board, cube, chair = (base.object(n) for n in ("yoga_roller", "surfboard", "cube", "chair"))
    heavy_chair = variant == "unsolvable" and rng.random() < 0.5
    cube_mass = {
        "tool": uniform(rng, 1.5, 5.0, 1) if light else uniform(rng, 6.0, 11.0, 1),
        "unsolvable": 10.0 if heavy_chair else uniform(rng, 25.0, 30.0, 1),
    }[variant]
    end = footprint(board)[0]  # the board's raised -x end
    edge = uniform(rng, end + 0.05, end + 0.2)  # the chair's +x edge, under the board
    under, _ = geometry.object_interval(geometry.object_parts(board), np.array([[edge, board.center[1]]]))
    chair_mass = uniform(rng, 6.0, 10.0, 1) if heavy_chair else chair.mass or 0.0
    if light:  # the chair and the board it drags out with it, under the push limit in every perturbed world
        pushable = QuadrupedLimits().max_push_mass / (1 + MASS_NOISE) - (board.mass or 0.0)
        chair_mass = min(chair_mass, float(np.floor(pushable * 10) / 10))
    # Notes without directions: the layout may mirror or turn the scene.
    scene = [
        roller.model_copy(update={"notes": "a yoga roller lying on its side, fixed to the floor"}),
        board.model_copy(
            update={
                "size": (board.size[0], board_width(layout, board.size[1]), board.size[2]),
                "notes": "a long board lying across the yoga roller; one end rests on the ground "
                "under the cube and the other end is raised",
            }
        ),
        cube.model_copy(
            update={
                "mass": cube_mass,
                "notes": f"a {'heavy ' if cube_mass > 5 else ''}cube on the lowered end of the board",
            }
        ),
        on_top(
            "chair",
            "box",
            (edge - chair.size[0] / 2, chair.center[1]),
            (*chair.size[:2], r4(under[0])),
            mass=chair_mass,
            notes=f"a {'heavy oak' if heavy_chair else 'small'} chair under the board's raised end",
        ),
    ]
    side = 1 if rng.random() < 0.5 else -1
    start = (uniform(rng, end, footprint(board)[2]), side * uniform(rng, 0.9, 1.4))
    body = (start[0] - 0.33, start[1] - 0.15, start[0] + 0.33, start[1] + 0.15)
    decoys = ["chair"] if heavy_chair else ["surfboard"] if variant == "unsolvable" else []
    spot = free_spot(
        rng, (0.4, 0.4), grow(hull([footprint(o) for o in scene]), 1.0), [footprint(o) for o in scene] + [body], 0.3
    )
    if variant == "tool" and spot is not None and rng.random() < 0.4:
        scene.append(
            on_top(
                "toolbox", "box", spot, (0.4, 0.4, 0.25), mass=uniform(rng, 8.0, 12.0, 1), notes="a heavy metal toolbox"
            )
        )
        decoys.append("toolbox")
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
    return Draft(
        variant=variant,
        category=base.category,
        instruction=base.instruction,
        robot={"type": "quadruped", "position": list(layout.point(start))},
        objects=[layout.place(o) for o in scene],
        goal=base.goal.model_dump(exclude_none=True),
        tools=[] if variant == "unsolvable" else ["surfboard"],
        decoys=decoys,
        layout=layout,
        varied=f"cube of {cube_mass:g} kg, chair of {chair_mass:g} kg at the board's raised end; "
        f"{'decoys: ' + ', '.join(decoys) if decoys else 'no decoys'}",
    )
