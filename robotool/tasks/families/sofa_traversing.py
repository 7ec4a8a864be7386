"""sofa_traversing: cross from one sofa to another over a gap that may be too wide to step over.

Description:
    The quadruped starts on sofa_1 and must stand on sofa_2. When the gap between them is wider than
    the robot's 0.10 m limit, it pushes a rigid surfboard lying on sofa_1 across the gap and walks over
    it. A strip of cloth lies under the board (it cannot carry load across a gap).
Randomizations:
    - the gap: 0.02-0.09 m (no tool), from 0.15 m to what the board bridges, or 0.30-0.45 m (unsolvable);
      the sofas' height (0.30-0.38 m); sofa_2's offset
      across the path; the robot's start on sofa_1; which side of the board the cloth lies on;
    - the board's length (the template's, or up to 0.1 m shorter; always at least the gap plus the
      template's overlap on the sofas) and mass (the template's +-15%);
    - decoys: the cloth always; in some solvable scenes a plank on the floor (the robot could step down
      to it but never climb back up); unsolvable scenes have no rigid board, only the cloth;
    - 0-3 fixed pieces of furniture on the floor away from the sofas; the whole scene mirrored, turned
      by quarter turns and shifted on the floor.
Success conditions:
    - the robot stands on top of sofa_2 at the end.
"""

from __future__ import annotations

import numpy as np

from robotool.task.scene import SceneObject
from robotool.tasks.families._common import (
    FLOOR_CLUTTER,
    Draft,
    board_width,
    draw_layout,
    draw_variant,
    footprint,
    grow,
    hull,
    on_top,
    r4,
    scatter,
    template,
    uniform,
)


def sofas(gap: float, height: float, offset: float = 0.0) -> list[SceneObject]:
    """The template's sofas, ``height`` high, sofa_2 ``gap`` metres beyond sofa_1's +x edge, ``offset`` across."""
    sofa_1, sofa_2 = (template("sofa_traversing").object(n) for n in ("sofa_1", "sofa_2"))
    x2 = sofa_1.center[0] + sofa_1.size[0] / 2 + gap + sofa_2.size[0] / 2
    return [
        on_top("sofa_1", "box", sofa_1.center[:2], (*sofa_1.size[:2], height), movable=False, notes=sofa_1.notes),
        on_top(
            "sofa_2",
            "box",
            (x2, sofa_1.center[1] + offset),
            (*sofa_2.size[:2], height),
            movable=False,
            notes=sofa_2.notes,
        ),
    ]


def build(rng: np.random.Generator) -> Draft:
    """One sofa_traversing scene from the random stream."""
    base = template("sofa_traversing")
    sofa_1, cloth, surfboard = (base.object(n) for n in ("sofa_1", "strip_of_cloth", "surfboard"))
    edge = sofa_1.center[0] + sofa_1.size[0] / 2  # where the gap starts
    bearing = surfboard.size[0] - footprint(base.object("sofa_2"))[0] + edge  # board length minus the gap
    variant = draw_variant(rng)
    layout = draw_layout(rng, arm=False)
    length = uniform(rng, surfboard.size[0] - 0.1, surfboard.size[0])
    gap = {
        "no_tool": uniform(rng, 0.02, 0.09),
        "tool": uniform(rng, 0.15, length - bearing),
        "unsolvable": uniform(rng, 0.30, 0.45),
    }[variant]
    height = uniform(rng, 0.30, 0.38)
    scene = sofas(gap, height, uniform(rng, -0.15, 0.15))
    side = 1 if rng.random() < 0.5 else -1
    scene.append(
        on_top(
            cloth.name,
            "cloth",
            (cloth.center[0], side * cloth.center[1]),
            cloth.size,
            height,
            mass=cloth.mass,
            notes=cloth.notes,
        )
    )
    decoys = [cloth.name]

    overhang = surfboard.center[0] + surfboard.size[0] / 2 - edge  # the template's board reaches over the gap

    width = board_width(layout, surfboard.size[1])

    def board(size_x: float, mass: float | None, notes: str | None) -> SceneObject:
        """A board on sofa_1 (on the cloth where they overlap), its +x end over the gap like the template's, so
        that the robot has room on sofa_1 to stand behind it and push."""
        return on_top(
            "surfboard",
            "box",
            (edge + overhang - size_x / 2, surfboard.center[1]),
            (size_x, width, surfboard.size[2]),
            height + cloth.size[2],
            mass=mass,
            notes=notes,
        )

    mass = uniform(rng, 0.85, 1.15) * (surfboard.mass or 3.0)
    if variant != "unsolvable":
        scene.append(board(length, r4(mass), surfboard.notes))
        if variant == "tool" and rng.random() < 0.4:
            y = (sofa_1.size[1] / 2 + 0.45) * -side
            scene.append(
                on_top(
                    "plank",
                    "box",
                    (sofa_1.center[0], y),
                    (1.1, 0.4, 0.05),
                    mass=2.0,
                    notes="a wooden plank lying on the floor",
                )
            )
            decoys.append("plank")
    # Unsolvable scenes have no rigid board at all, only the cloth: a heavy board can be shoved by the walking
    # robot until it wedges across the gap, and a short one can lodge in the gap as a filler.
    x0, y0 = base.robot.required_position()
    start = (uniform(rng, x0 - 0.02, x0 + 0.02), uniform(rng, y0 - 0.1, y0 + 0.1))  # the feet on sofa_1
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
    tools = ["surfboard"] if variant == "tool" else []
    return Draft(
        variant=variant,
        category=base.category,
        instruction=base.instruction,
        robot={"type": "quadruped", "position": list(layout.point(start))},
        objects=[layout.place(o) for o in scene],
        goal={"robot_on": "sofa_2"},
        tools=tools,
        decoys=decoys,
        layout=layout,
        varied=f"gap of {gap:.2f} m between {height:.2f} m high sofas, {length:.2f} m board; "
        f"decoys: {', '.join(decoys)}",
    )
