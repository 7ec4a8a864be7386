"""The scene as the planner reasons about it: object boxes, surfaces, and hypothetical placements.

Everything here reads only the task file (objects) through :mod:`robotool.task.geometry`. A :class:`Layout` can
move objects to hypothetical x-y placements, so a robot's macros can check a placement (does it overlap
something?) and predict its motions on it before anything is simulated.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from robotool.task import geometry
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task

CONTACT = 0.02  # m: boxes closer than this touch


@dataclass(frozen=True)
class Box:
    """An object's axis-aligned bounds in the world: x-y ``lo``/``hi`` and heights ``bottom``/``top``."""

    name: str
    lo: np.ndarray
    hi: np.ndarray
    bottom: float
    top: float

    @classmethod
    def of(cls, obj: SceneObject) -> Box:
        bounds = [p.aabb() for p in geometry.object_parts(obj)]
        lo = np.min([b[0] for b in bounds], axis=0)
        hi = np.max([b[1] for b in bounds], axis=0)
        return cls(obj.name, lo[:2], hi[:2], float(lo[2]), float(hi[2]))

    @property
    def center(self) -> np.ndarray:
        return (self.lo + self.hi) / 2

    @property
    def half(self) -> np.ndarray:
        return (self.hi - self.lo) / 2

    def moved_to(self, xy: np.ndarray) -> Box:
        """The same box with its x-y centre at ``xy``."""
        shift = np.asarray(xy, dtype=float) - self.center
        return Box(self.name, self.lo + shift, self.hi + shift, self.bottom, self.top)

    def overlap(self, other: Box) -> float:
        """How far the two boxes' x-y footprints overlap (<= 0: apart by that much)."""
        return float(np.min(np.minimum(self.hi, other.hi) - np.maximum(self.lo, other.lo)))

    def touches(self, other: Box) -> bool:
        return self.overlap(other) > -CONTACT


@dataclass
class Layout:
    """Load-bearing solids of a scene (cloth excluded), some possibly moved to new x-y centres.

    The objects' parts and boxes are built once per task (shared by every layout derived with :meth:`with_moved`),
    and each layout stacks its solids once per set of excluded names, and each object alone once per placement
    (:class:`geometry.PartStack`), so that the planner's many height queries cost one vectorised pass each."""

    task: Task
    moved: dict[str, np.ndarray] = field(default_factory=dict)
    _placed: dict[str, tuple[list[geometry.Part], Box]] = field(default_factory=dict, repr=False, compare=False)
    _stacks: dict[frozenset[str], geometry.PartStack] = field(default_factory=dict, repr=False, compare=False)
    _alone: dict[str, geometry.PartStack] = field(default_factory=dict, repr=False, compare=False)
    _boxes: tuple[list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = field(
        default=None, repr=False, compare=False
    )

    def box(self, name: str) -> Box:
        box = self._placed_as_in_task(name)[1]
        return box.moved_to(self.moved[name]) if name in self.moved else box

    def boxes(self, exclude: Iterable[str] = ()) -> list[Box]:
        skip = set(exclude)
        return [self.box(o.name) for o in self.task.objects if o.name not in skip]

    def with_moved(self, name: str, xy: np.ndarray) -> Layout:
        """A copy with ``name`` moved so that its x-y centre is ``xy``."""
        alone = {other: stack for other, stack in self._alone.items() if other != name}  # placed as here
        return Layout(self.task, {**self.moved, name: np.asarray(xy, dtype=float)}, _placed=self._placed, _alone=alone)

    def solids(self, exclude: Iterable[str] = ()) -> geometry.PartStack:
        """The load-bearing solids but ``exclude``, stacked for height queries."""
        skip = frozenset(exclude)
        if skip not in self._stacks:
            self._stacks[skip] = geometry.PartStack.of(
                [self._parts(o.name) for o in self.task.objects if o.shape != "cloth" and o.name not in skip]
            )
        return self._stacks[skip]

    def heights(self, xy: np.ndarray, exclude: Iterable[str] = ()) -> np.ndarray:
        """Surface height under each point (n, 2)."""
        return geometry.surface_height(np.atleast_2d(xy), self.solids(exclude))

    def tops(self, xy: np.ndarray, exclude: Iterable[str] = ()) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The surface height under each point (n, 2), as :meth:`heights` reads it, and the top of each load-bearing
        solid but ``exclude`` over them (NaN where it is not, as :meth:`top_of`), from one pass over the solids."""
        skip = frozenset(exclude)
        xy = np.atleast_2d(xy)
        top = self.solids(skip).solid_intervals(xy)[1]
        names = [o.name for o in self.task.objects if o.shape != "cloth" and o.name not in skip]
        return geometry.highest_top(top), dict(zip(names, top, strict=True))

    def top_of(self, name: str, xy: np.ndarray) -> np.ndarray:
        """The top of object ``name`` alone over each point (n, 2); NaN where it is not."""
        return self._interval(name, np.atleast_2d(xy))[1]

    def collides(self, box: Box, ignore: Iterable[str] = (), margin: float = 0.005) -> str | None:
        """The first other object that overlaps ``box``'s x-y footprint (not just touching) somewhere between
        ``box``'s bottom and top, or None."""
        skip = {box.name, *ignore}
        names, lo, hi, bottom, top = self._solid_boxes()
        overlap = np.min(np.minimum(box.hi, hi) - np.maximum(box.lo, lo), axis=1)  # as Box.overlap reads each
        near = (overlap > margin) & (top > box.bottom + margin) & (bottom < box.top - margin)
        for k in np.flatnonzero(near):
            if names[k] in skip:
                continue
            other = self.box(names[k])
            a, b = np.maximum(box.lo, other.lo) + margin, np.minimum(box.hi, other.hi) - margin  # the overlap
            grid = np.stack(np.meshgrid(np.linspace(a[0], b[0], 6), np.linspace(a[1], b[1], 6)), -1).reshape(-1, 2)
            low, high = self._interval(other.name, grid)
            if np.any((low < box.top - margin) & (high > box.bottom + margin)):
                return other.name
        return None

    def _solid_boxes(self) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The names (in the task's order), x-y bounds (k, 2) and bottoms and tops (k,) of the objects but the cloths,
        as :meth:`box` places them (read once per layout)."""
        if self._boxes is None:
            boxes = [self.box(o.name) for o in self.task.objects if o.shape != "cloth"]
            self._boxes = (
                [b.name for b in boxes],
                np.array([b.lo for b in boxes]).reshape(-1, 2),
                np.array([b.hi for b in boxes]).reshape(-1, 2),
                np.array([b.bottom for b in boxes]),
                np.array([b.top for b in boxes]),
            )
        return self._boxes

    def _interval(self, name: str, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest z of object ``name`` alone along vertical lines through ``xy`` (n, 2); NaN where
        missed (its parts stacked once per layout)."""
        if name not in self._alone:
            self._alone[name] = geometry.PartStack.of([self._parts(name)])
        low, high = self._alone[name].solid_intervals(xy)
        return low[0], high[0]

    def _parts(self, name: str) -> list[geometry.Part]:
        parts, box = self._placed_as_in_task(name)
        if name in self.moved:
            shift = np.append(self.moved[name] - box.center, 0.0)
            parts = [geometry.Part(p.kind, p.center + shift, p.half, p.rot) for p in parts]
        return parts

    def _placed_as_in_task(self, name: str) -> tuple[list[geometry.Part], Box]:
        """``name``'s parts and box where the task file places it (built once per task)."""
        if name not in self._placed:
            obj = self.task.object(name)
            self._placed[name] = (geometry.object_parts(obj), Box.of(obj))
        return self._placed[name]
