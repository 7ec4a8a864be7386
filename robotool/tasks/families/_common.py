"""What every task family shares: the instance model, variants, layouts (mirror, turn, shift) and clutter.

A family builds its scene in a canonical frame (the built-in template's), then places it with a
:class:`RigidPlacement` and finishes it with :func:`finish`, which validates the task and checks that the
family's intended ``needs_tool`` is what the geometry says (:func:`robotool.task.concepts.needs_tool`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from itertools import product
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict

from robotool.task import geometry
from robotool.task.concepts import needs_tool as geometry_needs_tool
from robotool.task.scene import SceneObject
from robotool.task.task_file import parse_task
from robotool.task.task_model import Category, Task

Variant = Literal["no_tool", "tool", "unsolvable"]
CLEARANCE = 0.001  # m between objects that stand against each other, so that rounding never interpenetrates them
SIDEWAYS_BOARD_WIDTH = 0.75  # m: wider than the quadruped is long (0.65 m), for boards it walks along flank first
Rect = tuple[float, float, float, float]  # x0, y0, x1, y1 on the floor or table


class Instance(BaseModel):
    """One generated task with its ground truth."""

    model_config = ConfigDict(frozen=True)

    family: str
    seed: int
    task: Task
    needs_tool: bool  # equals robotool.task.concepts.needs_tool(task)
    solvable: bool  # the scene holds what a solution needs within the robot's limits
    tools: list[str]  # the objects a solution uses; empty when none is needed
    decoys: list[str]  # objects that look useful but cannot serve
    mirrored: bool  # the canonical layout was reflected
    description: str  # what was varied, in one sentence


@functools.cache
def template(name: str) -> Task:
    """The built-in task a family varies: its objects carry the physically tuned sizes and masses."""
    from robotool.tasks.builtin import load  # the registry imports this package

    return load(name)


def draw_variant(rng: np.random.Generator) -> Variant:
    """About a third without a tool, half solvable with one, the rest with decoys only."""
    u = rng.random()
    return "no_tool" if u < 1 / 3 else "tool" if u < 0.85 else "unsolvable"


def r4(value: float) -> float:
    """A number rounded for a tidy task file (0.1 mm)."""
    return round(float(value), 4) + 0.0


def uniform(rng: np.random.Generator, low: float, high: float, digits: int = 4) -> float:
    """One draw from [low, high], rounded (to 0.1 mm by default; masses to 0.1 kg)."""
    return round(float(rng.uniform(low, high)), digits) + 0.0


def thing(
    name: str, shape: str, center: tuple[float, float, float] | list[float], size: tuple[float, ...], **fields: Any
) -> SceneObject:
    """A scene object with rounded numbers."""
    if "graspable_point" in fields:
        fields["graspable_point"] = tuple(r4(v) for v in fields["graspable_point"])
    return SceneObject(
        name=name, shape=shape, center=tuple(r4(v) for v in center), size=tuple(r4(v) for v in size), **fields
    )


def on_top(
    name: str, shape: str, xy: tuple[float, float], size: tuple[float, ...], base: float = 0.0, **fields: Any
) -> SceneObject:
    """An upright object with its bottom at height ``base`` (the ground by default)."""
    return thing(name, shape, (xy[0], xy[1], base + size[2] / 2), size, **fields)


# --- Layouts -------------------------------------------------------------------------------------------

_SYMMETRIC_AXES = {"hook": "z", "button": "yz"}  # local reflections that leave the shape unchanged


@dataclass(frozen=True)
class RigidPlacement:
    """A rigid placement of a canonical scene: reflect, turn about z by quarter turns, then shift."""

    mirror: Literal["", "x", "y"] = ""
    turns: int = 0
    shift: tuple[float, float] = (0.0, 0.0)

    @property
    def matrix(self) -> np.ndarray:
        reflect = np.diag([-1.0 if self.mirror == "x" else 1.0, -1.0 if self.mirror == "y" else 1.0, 1.0])
        c, s = round(math.cos(self.turns * math.pi / 2)), round(math.sin(self.turns * math.pi / 2))
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ reflect

    def point(self, p: tuple[float, ...]) -> tuple[float, ...]:
        """A point (x, y) or (x, y, z) placed by this layout."""
        q = self.matrix @ np.array([p[0], p[1], p[2] if len(p) > 2 else 0.0]) + np.array([*self.shift, 0.0])
        return tuple(r4(v) for v in q[: len(p)])

    def place(self, obj: SceneObject) -> SceneObject:
        """The object placed by this layout (a reflected hook turns over, so it stays an L of the same hand)."""
        size, axis, rpy = _orient(obj, self.matrix)
        update: dict[str, Any] = {"center": self.point(obj.center), "size": size, "axis": axis, "rpy": rpy}
        if obj.graspable_point is not None:
            update["graspable_point"] = self.point(obj.graspable_point)
        return obj.model_copy(update=update)

    def words(self) -> str:
        """The layout in words, e.g. 'mirrored in y, turned 90 deg, shifted by [0.4, -1.1]'."""
        bits = [f"mirrored in {self.mirror}"] if self.mirror else []
        if self.turns % 4:
            bits.append(f"turned {90 * (self.turns % 4)} deg")
        if any(self.shift):
            bits.append(f"shifted by [{self.shift[0]:g}, {self.shift[1]:g}]")
        return ", ".join(bits) or "template layout"


def _rpy(rot: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw in degrees with R = Rz Ry Rx (rounded; -180 reads as 180)."""
    pitch = math.degrees(math.asin(float(np.clip(-rot[2, 0], -1.0, 1.0))))
    roll = math.degrees(math.atan2(rot[2, 1], rot[2, 2]))
    yaw = math.degrees(math.atan2(rot[1, 0], rot[0, 0]))

    def tidy(a: float) -> float:
        return 180.0 if abs(a + 180) < 1e-6 else round(a, 6) + 0.0

    return tidy(roll), tidy(pitch), tidy(yaw)


def _orient(obj: SceneObject, matrix: np.ndarray) -> tuple[tuple[float, ...], str, tuple[float, float, float]]:
    """Size, cylinder axis and rpy of an object after a rotation or reflection ``matrix``.

    A reflection is absorbed by a local reflection the shape is symmetric under; of the equivalent
    orientations the one with the smallest angles wins, and a pure quarter turn of a symmetric shape
    swaps its x and y sizes instead of carrying a yaw.
    """
    rot = matrix @ geometry.rotation_matrix(obj.rpy)
    axes = _SYMMETRIC_AXES.get(obj.shape, "xyz")
    flips = [
        np.diag([-1.0 if (k in chosen) else 1.0 for k in "xyz"]) for n in range(4) for chosen in product(axes, repeat=n)
    ]
    det = round(float(np.linalg.det(matrix)))
    candidates = [_rpy(rot @ f) for f in flips if round(float(np.linalg.det(f))) == det]
    rpy = min(candidates, key=lambda a: (sum(abs(v) for v in a), a))
    size, axis = obj.size, obj.axis
    if obj.shape in ("box", "cloth", "cylinder") and rpy[:2] == (0.0, 0.0) and abs(abs(rpy[2]) - 90) < 1e-6:
        size, rpy = (size[1], size[0], size[2]), (0.0, 0.0, 0.0)
        axis = "y" if axis == "x" else "x" if axis == "y" else axis
    return size, axis, rpy


def draw_layout(rng: np.random.Generator, arm: bool) -> RigidPlacement:
    """The arm's layout may only mirror in y (its workspace is symmetric in y alone); a quadruped's scene
    may also turn and shift anywhere on the floor."""
    if arm:
        return RigidPlacement(mirror="y" if rng.random() < 0.5 else "")
    drawn = str(rng.choice(["", "", "x", "y"]))
    mirror: Literal["", "x", "y"] = "x" if drawn == "x" else "y" if drawn == "y" else ""
    turns = int(rng.integers(0, 4))
    shift = (round(float(rng.uniform(-1.5, 1.5)), 2), round(float(rng.uniform(-1.5, 1.5)), 2))
    return RigidPlacement(mirror=mirror, turns=turns, shift=shift)


def board_width(layout: RigidPlacement, width: float) -> float:
    """The width of a board the quadruped walks along (along the template's x): ``width`` as in the template, or
    :data:`SIDEWAYS_BOARD_WIDTH` when the layout turns the scene a quarter, so that the robot can walk along the board
    without a turn, flank first, its feet as far apart across the board as its body is long."""
    return width if layout.turns % 2 == 0 else max(width, SIDEWAYS_BOARD_WIDTH)


# --- Clutter --------------------------------------------------------------------------------------------


def footprint(obj: SceneObject) -> Rect:
    """The object's x-y bounding rectangle."""
    boxes = [p.aabb() for p in geometry.object_parts(obj)]
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))


def grow(rect: Rect, margin: float) -> Rect:
    return (rect[0] - margin, rect[1] - margin, rect[2] + margin, rect[3] + margin)


def hull(rects: list[Rect]) -> Rect:
    """The smallest rectangle holding all of ``rects``."""
    return (min(r[0] for r in rects), min(r[1] for r in rects), max(r[2] for r in rects), max(r[3] for r in rects))


def _meets(a: Rect, b: Rect) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def free_spot(
    rng: np.random.Generator, size_xy: tuple[float, float], region: Rect, avoid: list[Rect], margin: float
) -> tuple[float, float] | None:
    """A centre in ``region`` whose rectangle keeps ``margin`` from every rectangle in ``avoid``."""
    hx, hy = size_xy[0] / 2, size_xy[1] / 2
    for _ in range(60):
        x, y = uniform(rng, region[0] + hx, region[2] - hx), uniform(rng, region[1] + hy, region[3] - hy)
        rect = grow((x - hx, y - hy, x + hx, y + hy), margin)
        if not any(_meets(rect, a) for a in avoid):
            return x, y
    return None


def spot_for(
    rng: np.random.Generator, size_xy: tuple[float, float], region: Rect, avoid: list[Rect], margin: float
) -> tuple[float, float]:
    """Like :func:`free_spot` for an object the scene cannot do without."""
    spot = free_spot(rng, size_xy, region, avoid, margin)
    if spot is None:
        raise RuntimeError(f"no room for a {size_xy[0]} x {size_xy[1]} m object in {region}")
    return spot


@dataclass(frozen=True)
class Clutter:
    """A kind of plain object the families scatter as distractors."""

    name: str
    shape: Literal["box", "cylinder"]
    size: tuple[float, float, float]
    mass: float
    notes: str


ARM_CLUTTER = (
    Clutter("mug", "cylinder", (0.08, 0.08, 0.10), 0.3, "a coffee mug"),
    Clutter("book", "box", (0.15, 0.10, 0.03), 0.4, "a paperback book lying flat"),
    Clutter("sponge", "box", (0.09, 0.06, 0.04), 0.05, "a kitchen sponge"),
    Clutter("tin", "cylinder", (0.07, 0.07, 0.05), 0.2, "a small round tin"),
)
FLOOR_CLUTTER = (
    Clutter("cabinet", "box", (0.5, 0.4, 0.8), 20.0, "a cabinet"),
    Clutter("plant_pot", "cylinder", (0.35, 0.35, 0.5), 8.0, "a potted plant"),
    Clutter("side_table", "box", (0.5, 0.5, 0.45), 6.0, "a side table"),
    Clutter("bin", "cylinder", (0.3, 0.3, 0.4), 2.0, "a waste bin"),
)


def scatter(
    rng: np.random.Generator,
    objects: list[SceneObject],
    count: int,
    kinds: tuple[Clutter, ...],
    region: Rect,
    keep_out: list[Rect],
    movable: bool,
    margin: float,
    base: float = 0.0,
) -> list[SceneObject]:
    """Up to ``count`` distractors in ``region``, clear of the objects and of ``keep_out`` by ``margin``.

    Fixed distractors cannot be pushed into use; movable ones stay light clutter.
    """
    avoid = [footprint(o) for o in objects] + list(keep_out)
    placed: list[SceneObject] = []
    for _ in range(count):
        kind = kinds[int(rng.integers(len(kinds)))]
        spot = free_spot(rng, kind.size[:2], region, avoid, margin)
        if spot is None:
            continue
        index = sum(o.name.startswith(kind.name) for o in placed) + 1
        mass = {"mass": kind.mass} if movable else {}
        obj = on_top(
            f"{kind.name}_{index}", kind.shape, spot, kind.size, base, movable=movable, notes=kind.notes, **mass
        )
        placed.append(obj)
        avoid.append(footprint(obj))
    return placed


# --- Finishing ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Draft:
    """A family's scene, placed, with what it knows by construction."""

    variant: Variant
    category: Category  # used when a tool is needed
    instruction: str
    robot: dict[str, Any]
    objects: list[SceneObject]
    goal: dict[str, Any]
    tools: list[str]
    decoys: list[str]
    layout: RigidPlacement
    varied: str  # what the family varied, in words


def finish(family: str, seed: int, draft: Draft) -> Instance:
    """Validate the draft as a task file and attach its ground truth."""
    name = f"{family}_{seed}"
    data = {
        "format": 1,
        "name": name,
        "category": "no_tool" if draft.variant == "no_tool" else draft.category,
        "instruction": draft.instruction,
        "robot": draft.robot,
        "objects": [o.model_dump(mode="json", exclude_defaults=True) for o in draft.objects],
        "goal": draft.goal,
    }
    task = parse_task(data, source=name)
    needs = geometry_needs_tool(task)
    if needs != (draft.variant != "no_tool"):
        raise AssertionError(f"{name}: built as {draft.variant!r} but the geometry says needs_tool={needs}")
    return Instance(
        family=family,
        seed=seed,
        task=task,
        needs_tool=needs,
        solvable=draft.variant != "unsolvable",
        tools=draft.tools,
        decoys=draft.decoys,
        mirrored=bool(draft.layout.mirror),
        description=f"{draft.varied}; {draft.layout.words()}.",
    )
