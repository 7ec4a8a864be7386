"""button_pressing: press a button whose face may lie beyond the arm's reach.

Description:
    The arm must press a fixed button (its face on the -x side, pressed after 1 cm of travel). When the
    face lies beyond x = 0.45 m, the arm chains magnetic cubes into a stick held in the gripper and presses
    with the chain's far end.
Randomizations:
    - the face's x: inside the workspace (no tool) or beyond it but within the chain's reach
      (0.45 + 0.015 + 0.03 (n - 1) m for n cubes, minus 2 cm); the button's y;
    - the number (3-4) and places of the magnetic cubes, clear of the line in front of the button;
    - decoys: plain wooden cubes that do not stick; unsolvable scenes have only two magnetic cubes and a
      face beyond what two cubes can reach, held (:func:`chain_reach`) or pushed loose by the closed fingers
      (:func:`push_reach`, honest tool use: the joined pair is a stick pushed rather than held), and no other
      movable object;
    - 0-2 fixed table-top distractors; the layout mirrored in y.
Success conditions:
    - the button is pressed at some moment.
"""

from __future__ import annotations

import numpy as np

from robotool.robots.arm.arm_config import ARM
from robotool.task.scene import SceneObject
from robotool.tasks.families._common import (
    ARM_CLUTTER,
    Draft,
    draw_layout,
    draw_variant,
    on_top,
    scatter,
    spot_for,
    uniform,
)

CUBE = 0.03
BUTTON = (0.24, 0.10, 0.08)


def chain_reach(cubes: int) -> float:
    """Farthest x the front of a held chain of magnetic cubes reaches."""
    return 0.45 + CUBE / 2 + CUBE * (cubes - 1)


PRESS = 0.01  # m a face must be pushed in to count as pressed


def push_reach(cubes: int) -> float:
    """Farthest x the front of a row of joined magnetic cubes reaches when the closed fingers push it loose."""
    return 0.45 + ARM.finger_half[0] + CUBE * cubes  # the closed fingers reach half a pad past the centre


def cubes(
    rng: np.random.Generator, prefix: str, count: int, avoid: list[tuple[float, float, float, float]], magnetic: bool
) -> list[SceneObject]:
    """``count`` small cubes on the table within reach, clear of ``avoid`` (which grows as they are placed)."""
    notes = (
        "a small magnetic cube; magnetic cubes stick together when they touch" if magnetic else "a small wooden cube"
    )
    placed = []
    for i in range(count):
        spot = spot_for(rng, (CUBE, CUBE), (0.15, -0.35, 0.43, 0.35), avoid, 0.03)
        placed.append(
            on_top(f"{prefix}{i + 1}", "box", spot, (CUBE, CUBE, CUBE), mass=0.05, magnetic=magnetic, notes=notes)
        )
        avoid.append((spot[0] - CUBE / 2, spot[1] - CUBE / 2, spot[0] + CUBE / 2, spot[1] + CUBE / 2))
    return placed


def build(rng: np.random.Generator) -> Draft:
    """One button_pressing scene from the random stream."""
    variant = draw_variant(rng)
    layout = draw_layout(rng, arm=True)
    count = {"no_tool": int(rng.integers(3, 5)), "tool": int(rng.integers(3, 5)), "unsolvable": 2}[variant]
    face = {
        "no_tool": uniform(rng, 0.30, 0.43),
        "tool": uniform(rng, 0.47, chain_reach(count) - 0.02),
        "unsolvable": uniform(rng, chain_reach(2) + 0.035, chain_reach(2) + 0.06),
    }[variant]
    by = uniform(rng, -0.15, 0.15)
    button = on_top(
        "button",
        "button",
        (face + BUTTON[0] / 2, by),
        BUTTON,
        movable=False,
        notes="a button housing; its face on the -x side is pressed by pushing it 1 cm towards +x",
    )
    corridor = (0.10, by - 0.08, face + BUTTON[0], by + 0.08)
    base = (-0.15, -0.15, 0.15, 0.15)
    avoid = [corridor, base]
    scene = [*cubes(rng, "magnetic_cube", count, avoid, magnetic=True), button]
    decoys = [o.name for o in scene if o.magnetic] if variant == "unsolvable" else []
    if variant != "unsolvable" and rng.random() < 0.5:
        plain = cubes(rng, "wooden_cube", int(rng.integers(1, 3)), avoid, magnetic=False)
        scene += plain
        decoys += [o.name for o in plain]
    scene += scatter(
        rng,
        scene,
        int(rng.integers(0, 3)),
        ARM_CLUTTER,
        (-0.28, -0.44, 0.42, 0.44),
        [corridor, base, (0.12, -0.38, 0.46, 0.38)],
        movable=False,
        margin=0.04,
    )
    tools = [o.name for o in scene if o.magnetic] if variant == "tool" else []
    outside = face - 0.45
    where = f"{outside:.2f} m beyond the workspace" if outside > 0 else "inside the workspace"
    return Draft(
        variant=variant,
        category="tool_manufacturing",
        instruction="Press the button.",
        robot={"type": "arm"},
        objects=[layout.place(o) for o in scene],
        goal={"pressed": "button"},
        tools=tools,
        decoys=decoys,
        layout=layout,
        varied=f"button face at x = {face:.2f} m ({where}), {count} magnetic cubes; "
        f"{'decoys: ' + ', '.join(decoys) if decoys else 'no decoys'}",
    )
