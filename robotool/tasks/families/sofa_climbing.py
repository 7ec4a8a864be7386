"""sofa_climbing: get on top of a sofa that may be too high to climb directly.

Description:
    The quadruped starts on the floor and must stand on the sofa. A 0.24 m box stands against the sofa
    and a 0.12 m box lies elsewhere. When the sofa is higher than the 0.12 m climb limit, the robot pushes
    the low box against the high one (or, for a sofa of at most 0.24 m, against the sofa) and climbs the
    steps.
Randomizations:
    - the sofa's height: 0.06-0.12 m (no tool), 0.16-0.24 m (one step) or 0.28-0.36 m (two steps);
    - the low box's place and mass (2-4 kg), the high box's place along the sofa and mass (3.5-4.8 kg),
      the robot's start;
    - decoys: a crate too tall to climb onto (0.30 m) or a box of step height too heavy to push (7-10 kg);
      in unsolvable scenes such a decoy replaces the low box;
    - 0-3 fixed pieces of furniture away from the scene; the whole scene mirrored, turned by quarter
      turns and shifted on the floor.
Success conditions:
    - the robot stands on top of the sofa at the end.
"""

from __future__ import annotations

import numpy as np

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
    uniform,
)

BOX = (0.4, 0.6)  # footprint of the boxes
LOW, HIGH, TALL = 0.12, 0.24, 0.30


def decoy(rng: np.random.Generator, name: str, xy: tuple[float, float]) -> SceneObject:
    """A box that looks like a step but is too tall to climb onto or too heavy to push."""
    if rng.random() < 0.5:
        return on_top(name, "box", xy, (*BOX, TALL), mass=3.0, notes="a tall cardboard crate")
    return on_top(name, "box", xy, (*BOX, LOW), mass=uniform(rng, 7.0, 10.0, 1), notes="a box full of books")


def build(rng: np.random.Generator) -> Draft:
    """One sofa_climbing scene from the random stream."""
    variant = draw_variant(rng)
    layout = draw_layout(rng, arm=False)
    one_step = variant == "tool" and rng.random() < 0.3
    height = (
        uniform(rng, 0.06, 0.12)
        if variant == "no_tool"
        else uniform(rng, 0.16, 0.24)
        if one_step
        else uniform(rng, 0.28, 0.36)
    )
    box_1_xy = (uniform(rng, 0.8, 1.6), uniform(rng, -0.8, 0.8))
    scene = [
        on_top(
            "sofa",
            "box",
            (3.0, 0.2),
            (0.9, 1.5, height),
            movable=False,
            notes="a sofa" if height > LOW else "a low sofa",
        ),
        on_top(
            "box_2",
            "box",
            (2.35 - CLEARANCE, uniform(rng, -0.25, 0.65)),
            (*BOX, HIGH),
            mass=uniform(rng, 3.5, 4.8, 1),
            notes="a cardboard box standing against the sofa",
        ),
    ]
    decoys: list[str] = []
    if variant == "unsolvable":
        scene.append(decoy(rng, "box_1", box_1_xy))
        decoys.append("box_1")
    else:
        scene.append(
            on_top("box_1", "box", box_1_xy, (*BOX, LOW), mass=uniform(rng, 2.0, 4.0, 1), notes="a cardboard box")
        )
        spot = free_spot(rng, BOX, (0.6, -1.4, 1.8, 1.4), [footprint(o) for o in scene], 0.3)
        if variant == "tool" and spot is not None and rng.random() < 0.4:
            scene.append(decoy(rng, "box_3", spot))
            decoys.append("box_3")
    start = (0.0, uniform(rng, -0.4, 0.4))
    body = (start[0] - 0.33, start[1] - 0.15, start[0] + 0.33, start[1] + 0.15)
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
    tools = {"no_tool": [], "unsolvable": [], "tool": ["box_1"] if one_step else ["box_1", "box_2"]}[variant]
    return Draft(
        variant=variant,
        category="sequential_tool_use",
        instruction="You want to stand on top of the sofa.",
        robot={"type": "quadruped", "position": list(layout.point(start))},
        objects=[layout.place(o) for o in scene],
        goal={"robot_on": "sofa"},
        tools=tools,
        decoys=decoys,
        layout=layout,
        varied=f"sofa {height:.2f} m high; {'decoys: ' + ', '.join(decoys) if decoys else 'no decoys'}",
    )
