"""can_grasping: grasp a can that may stand beyond the arm's reach, next to a sheet of paper.

Description:
    The arm must hold the can. When the can stands beyond x = 0.45 m, the arm grasps a stick, pushes
    the can onto a strip of paper whose near edge lies inside the workspace, then drags the paper (and
    the can on it) in and grasps the can.
Randomizations:
    - the can: inside the workspace (no tool), beyond it between the stick and the paper (stick, then
      paper), or beyond it already on the paper (paper only);
    - the positions of the paper and the stick (by a few centimetres);
    - decoys: a chopstick too short to touch a far can (the only pushing tool in unsolvable scenes;
      an extra object in some solvable ones);
    - 0-2 light table-top distractors clear of the paper's drag path; the layout mirrored in y.
Success conditions:
    - the gripper holds the can at the end.
"""

from __future__ import annotations

import numpy as np

from robotool.tasks.families._common import (
    ARM_CLUTTER,
    Draft,
    draw_layout,
    draw_variant,
    on_top,
    scatter,
    uniform,
)

CAN = (0.05, 0.05, 0.08)
PAPER = (0.6, 0.4, 0.002)


def build(rng: np.random.Generator) -> Draft:
    """One can_grasping scene from the random stream."""
    variant = draw_variant(rng)
    layout = draw_layout(rng, arm=True)
    px, py = uniform(rng, 0.58, 0.64), uniform(rng, 0.20, 0.24)
    sx, sy = uniform(rng, 0.58, 0.64), uniform(rng, -0.14, -0.11)
    on_paper = variant == "tool" and rng.random() < 0.3
    if variant == "no_tool":
        can_xy = (uniform(rng, 0.25, 0.40), uniform(rng, -0.34, -0.22))
    elif on_paper:
        can_xy = (uniform(rng, 0.64, 0.74), uniform(rng, py - 0.1, py + 0.1))
    else:
        low = 0.66 if variant == "unsolvable" else 0.64
        can_xy = (uniform(rng, low, low + 0.10), uniform(rng, sy + 0.045, py - PAPER[1] / 2 - 0.03))
    paper = on_top(
        "strip_of_paper",
        "box",
        (px, py),
        PAPER,
        mass=0.05,
        friction=1.0,
        graspable_point=(px - PAPER[0] / 2, py, PAPER[2]),
        notes="a thin sheet of paper lying flat",
    )
    scene = [paper]
    decoys: list[str] = []
    if variant == "unsolvable":
        length = uniform(rng, 0.12, 0.18)
        scene.append(
            on_top(
                "chopstick",
                "box",
                (0.30 + length / 2, sy),
                (length, 0.02, 0.02),
                mass=0.02,
                graspable_point=(0.34, sy, 0.02),
                notes="a short thin chopstick lying along x",
            )
        )
        decoys.append("chopstick")
    else:
        scene.append(
            on_top(
                "stick",
                "box",
                (sx, sy),
                (0.5, 0.02, 0.02),
                mass=0.1,
                graspable_point=(sx - 0.2, sy, 0.02),
                notes="a thin straight stick lying along x",
            )
        )
        if rng.random() < 0.4:
            length = uniform(rng, 0.12, 0.18)
            scene.append(
                on_top(
                    "chopstick",
                    "box",
                    (-0.2 + length / 2, -0.32),
                    (length, 0.02, 0.02),
                    mass=0.02,
                    graspable_point=(-0.16, -0.32, 0.02),
                    notes="a short thin chopstick lying along x",
                )
            )
            decoys.append("chopstick")
    can = on_top(
        "can", "cylinder", can_xy, CAN, PAPER[2] if on_paper else 0.0, mass=0.2, notes="a soda can standing upright"
    )
    scene.append(can)
    drag = (-0.30, py - PAPER[1] / 2, px + PAPER[0] / 2, py + PAPER[1] / 2)  # where the paper is dragged
    push = (sx - 0.25, sy - 0.03, 0.94, py)  # where the stick pushes the can
    base = (-0.15, -0.15, 0.15, 0.15)
    scene += scatter(
        rng,
        scene,
        int(rng.integers(0, 3)),
        ARM_CLUTTER,
        (-0.28, -0.44, 0.42, 0.44),
        [drag, push, base],
        movable=True,
        margin=0.04,
    )
    tools = {"no_tool": [], "unsolvable": [], "tool": ["strip_of_paper"] if on_paper else ["stick", "strip_of_paper"]}[
        variant
    ]
    where = (
        "inside the workspace"
        if variant == "no_tool"
        else f"{can_xy[0] - 0.45:.2f} m beyond the workspace{' on the paper' if on_paper else ''}"
    )
    return Draft(
        variant=variant,
        category="sequential_tool_use",
        instruction="Grasp the can.",
        robot={"type": "arm"},
        objects=[layout.place(o) for o in scene],
        goal={"grasped": "can"},
        tools=tools,
        decoys=decoys,
        layout=layout,
        varied=f"can at x = {can_xy[0]:.2f} m ({where}); {'decoys: ' + ', '.join(decoys) if decoys else 'no decoys'}",
    )
