"""A scene's objects as a task file gives them (sizes in metres, masses in kilograms): :class:`SceneObject`."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictBool,
    StringConstraints,
    model_validator,
)

from robotool.task import geometry

DEFAULT_DENSITY = 300.0  # kg/m^3, for movable objects without a mass
MASS_NOISE = 0.15  # a movable object's mass is scaled by up to this much either way in a perturbed world
PRESS_TRAVEL = 0.01  # m: a button counts as pressed after its face travelled this far
DEFAULT_BUTTON_STIFFNESS = 300.0  # N/m: 3 N at the press travel, like a real push button
DEFAULT_BUTTON_TRAVEL = 0.02  # m the face can be pushed in
SHEET_THICKNESS = 0.003  # m: a box this thin or thinner is a sheet (paper), not a rigid plate ...
SHEET_AREAL_DENSITY = 1.0  # kg/m^2: ... unless it weighs more than this per square metre of its face (heavy card is
# about 0.5; a 3 mm box of the default density 0.9; a 3 mm steel plate 23)

MAX_COORDINATE = 1000.0
"""m (and degrees for ``rpy``): the largest coordinate a task file may give. A scene is a room or a yard; a centre of
1e308 m is a mistake, and the geometry checks would overflow on it."""
MAX_LENGTH = 1000.0
"""m: the largest size, thickness, drop or height a task file may give (also the largest friction coefficient)."""
MAX_MASS = 100_000.0
"""kg: the heaviest object a task file may give (a loaded lorry; a real task's heaviest is under a tonne)."""

MIN_LENGTH = 0.0001
"""m: the smallest size, thickness, drop or height a task file may give (0.1 mm, a sheet of paper's thickness)."""
MIN_MASS = 0.001
"""kg: the lightest movable object (1 g, given or from the volume). With :data:`MIN_LENGTH` the lightest, smallest
body the simulator builds has a mass and a moment of inertia (at least ``MIN_MASS * MIN_LENGTH**2 / 12``, about 1e-12
kg m^2) far above the 1e-15 (``mjMINVAL``) below which MuJoCo refuses to build it; a size of 1e-300 m divided by
zero."""
MIN_CLOTH_MASS = 0.01
"""kg per metre of a cloth's length: the simulator builds a cloth as a chain of links about 10 cm long, each as heavy
as :data:`MIN_MASS` at least (a 200 m cloth of 1 g did not build)."""
MAX_CLOTH_LENGTH = 20.0
"""m: the longest cloth, 200 links (a cloth of 120 m nests its links deeper than the simulator builds)."""
MIN_BUTTON_STIFFNESS = 1.0
"""N/m: the softest button spring a task file may give (0.01 N at the press travel; a softer one would be described
as a spring of 0 N/m)."""
MAX_BUTTON_STIFFNESS = 15_000.0
"""N/m: the stiffest button spring a task file may give, 150 N at the press travel: more than a robot that presses
buttons pushes (100 N at most), so a button too stiff for it can still be given. The simulator follows the 20 g face
on its spring stably at its 2 ms step up to ``4 m / dt^2`` = 20000 N/m; a face let go 1.5 cm in on a 30000 N/m spring
blew up the simulation."""


def _not_boolean(value: object) -> object:
    """A number is refused as true or false (pydantic would read them as 1 and 0)."""
    if isinstance(value, bool):
        raise ValueError(f"a number is needed, not a boolean (got {str(value).lower()})")
    return value


def _at_least(smallest: float, what: str) -> AfterValidator:
    """A lower bound, above 0, whose message names what it bounds."""

    def check(value: float) -> float:
        if value < smallest:
            raise ValueError(f"{value:g} is below the smallest {what} a task file may give, {smallest:g}")
        return value

    return AfterValidator(check)


def _between(low: float, high: float, what: str, unit: str) -> AfterValidator:
    """A closed range whose message names what it bounds and the range."""

    def check(value: float) -> float:
        if not low <= value <= high:
            raise ValueError(f"{what} lies between {low:g} and {high:g} {unit} (got {value:g})")
        return value

    return AfterValidator(check)


NOT_BOOLEAN = BeforeValidator(_not_boolean)
Name = Annotated[str, StringConstraints(pattern=r"^[a-z0-9_]+$", min_length=1, max_length=64)]
Positive = Annotated[float, Field(gt=0, le=MAX_LENGTH, allow_inf_nan=False), NOT_BOOLEAN]
PositiveLength = Annotated[Positive, _at_least(MIN_LENGTH, "length (m)")]
Coordinate = Annotated[float, Field(ge=-MAX_COORDINATE, le=MAX_COORDINATE, allow_inf_nan=False), NOT_BOOLEAN]
Mass = Annotated[float, Field(gt=0, le=MAX_MASS, allow_inf_nan=False), NOT_BOOLEAN, _at_least(MIN_MASS, "mass (kg)")]
ButtonStiffness = Annotated[
    float,
    Field(allow_inf_nan=False),
    NOT_BOOLEAN,
    _between(MIN_BUTTON_STIFFNESS, MAX_BUTTON_STIFFNESS, "a button's spring stiffness", "N/m"),
]
Vec3 = tuple[Coordinate, Coordinate, Coordinate]
Size3 = tuple[PositiveLength, PositiveLength, PositiveLength]
Shape = Literal["box", "cylinder", "hook", "cloth", "button"]


def reserved_name(name: str) -> str | None:
    """Why an object may not have this name, or None: the simulator names its bodies, geoms, joints and welds after
    the objects (``<name>``, ``<name>__geom0``, ``magnet__<a>__<b>``) beside its own (``world``; the robot's parts
    ``robot``, ``robot_gripper``, ``robot_foot0``, ...), and two equal names would not build."""
    if name == "world":
        return "'world' is reserved: it is the simulator's name for the world itself"
    if name.startswith("robot"):
        return f"{name!r} is reserved: names starting with 'robot' are the robot's (its parts in the simulator)"
    if "__" in name or name.startswith("_") or name.endswith("_"):
        return (
            f"{name!r}: '_' stands only singly between letters or digits (the simulator names an object's parts "
            "<name>__<part>, and such a name could be another's)"
        )
    return None


def number_text(value: float) -> str:
    """A number (metres, kilograms) as robotool writes it for people and models: at most three decimals, no
    trailing zeros."""
    return f"{value:.3f}".rstrip("0").rstrip(".")


class StrictModel(BaseModel):
    """A task-file model: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid")


class Fragile(StrictModel):
    """A fragile object breaks if it falls more than ``max_drop`` metres onto a hard surface."""

    max_drop: PositiveLength


class SceneObject(StrictModel):
    """One object of the scene. Sizes are the bounding box before rotation, in metres."""

    name: Name
    shape: Shape
    center: Vec3
    size: Size3
    rpy: Vec3 = (0.0, 0.0, 0.0)
    axis: Literal["x", "y", "z"] = "z"
    thickness: PositiveLength = 0.02
    movable: StrictBool = True
    mass: Mass | None = None
    friction: Positive | None = None
    magnetic: StrictBool = False
    soft: StrictBool = False
    fragile: Fragile | None = None
    graspable_point: Vec3 | None = None
    stiffness: ButtonStiffness | None = None  # buttons: spring, N/m
    travel: PositiveLength | None = None  # buttons: how far the face can be pushed in, m
    notes: str | None = None

    @model_validator(mode="before")
    @classmethod
    def _buttons_are_fixed(cls, data: object) -> object:
        """A button's housing is fixed: ``movable`` defaults to false for it, and true is an error."""
        if isinstance(data, dict) and data.get("shape") == "button":
            if data.get("movable", False) is not False:
                raise ValueError("a button's housing is fixed in place: leave out 'movable' or write movable: false")
            data = {**data, "movable": False}
        return data

    @model_validator(mode="after")
    def _shape_options(self) -> SceneObject:
        if self.axis != "z" and self.shape != "cylinder":
            raise ValueError(f"'axis' applies to cylinders only, not to a {self.shape}")
        if self.thickness != 0.02 and self.shape != "hook":
            raise ValueError(f"'thickness' applies to hooks only, not to a {self.shape}")
        for key in ("stiffness", "travel"):
            if getattr(self, key) is not None and self.shape != "button":
                raise ValueError(f"'{key}' applies to buttons only, not to a {self.shape}")
        if self.shape == "button" and not PRESS_TRAVEL < self.button_travel <= self.size[0] / 2:
            raise ValueError(
                f"button travel {self.button_travel} m must exceed the {PRESS_TRAVEL} m that counts "
                f"as pressed and be at most half the button's length ({self.size[0] / 2} m)"
            )
        if self.shape == "hook" and self.thickness >= min(self.size[0], self.size[1]):
            raise ValueError(
                f"hook thickness {self.thickness} m must be smaller than its length and head "
                f"({self.size[0]} m x {self.size[1]} m)"
            )
        return self._movable_options()

    def _movable_options(self) -> SceneObject:
        """``mass`` and ``graspable_point`` are a movable object's (a fixed thin box's mass says whether it is a
        sheet), and a movable object weighs at least :data:`MIN_MASS`."""
        if not self.movable and self.mass is not None and not self.is_thin_box:
            raise ValueError(
                f"'mass' applies to movable objects only (and to a fixed box at most {SHEET_THICKNESS * 1000:g} mm "
                "thick, a sheet or a plate by its mass); a fixed object does not move"
            )
        if not self.movable and self.graspable_point is not None:
            raise ValueError("'graspable_point' applies to movable objects only; the gripper holds nothing fixed")
        if self.movable and self.effective_mass < MIN_MASS:
            raise ValueError(
                f"it weighs {self.effective_mass:.2g} kg at the default {DEFAULT_DENSITY:g} kg/m^3 of its volume, "
                f"less than the lightest a task file may give; give it a 'mass' of at least {MIN_MASS:g} kg"
            )
        return self if self.shape != "cloth" else self._cloth_options()

    def _cloth_options(self) -> SceneObject:
        """A cloth is movable (the simulator builds it as free hinged links that drape and slide: found by an
        adversarial run, a cloth declared fixed was built free, and every rule that weighs what the robot moves or
        what bears its weight passed it by as fixed), at most :data:`MAX_CLOTH_LENGTH` long and
        :data:`MIN_CLOTH_MASS` per metre heavy, :data:`MIN_MASS` at least."""
        if not self.movable:
            raise ValueError(
                "a cloth drapes and slides: it cannot be fixed in place; leave out 'movable' (or make it a box, "
                "which may be fixed)"
            )
        length = max(self.size[:2])
        if length > MAX_CLOTH_LENGTH:
            raise ValueError(f"a cloth is at most {MAX_CLOTH_LENGTH:g} m long (this one {length:g} m)")
        lightest = max(MIN_MASS, MIN_CLOTH_MASS * length)
        if self.effective_mass < lightest:
            raise ValueError(
                f"a cloth weighs at least {MIN_CLOTH_MASS:g} kg per metre of its length and {MIN_MASS:g} kg in all, "
                f"{lightest:.3g} kg for this one (it weighs {self.effective_mass:.3g} kg)"
            )
        return self

    @property
    def button_stiffness(self) -> float:
        """A button's spring stiffness in N/m: as given, or :data:`DEFAULT_BUTTON_STIFFNESS`."""
        return self.stiffness if self.stiffness is not None else DEFAULT_BUTTON_STIFFNESS

    @property
    def button_travel(self) -> float:
        """How far a button's face can be pushed in, m: as given, or :data:`DEFAULT_BUTTON_TRAVEL`."""
        return self.travel if self.travel is not None else DEFAULT_BUTTON_TRAVEL

    @property
    def volume(self) -> float:
        """Volume in m^3 of the solid the simulator builds."""
        sx, sy, sz = self.size
        if self.shape == "cylinder":
            parts = geometry.object_parts(self)
            r, half_len = parts[0].half[0], parts[0].half[2]
            return math.pi * r * r * 2 * half_len
        if self.shape == "hook":
            t = self.thickness
            return (sx * t + (sy - t) * t) * sz
        return sx * sy * sz

    @property
    def effective_mass(self) -> float:
        """The mass in kg: as given, or from the default density."""
        return self.mass if self.mass is not None else DEFAULT_DENSITY * self.volume

    @property
    def is_sheet(self) -> bool:
        """Whether it is a sheet (a box at most :data:`SHEET_THICKNESS` thick and at most :data:`SHEET_AREAL_DENSITY`
        per square metre of its face, like paper or card): it cannot push or lift anything with its edge, and the
        gripper pinches a fold of it. A heavier thin box is a rigid plate (a 3 mm steel plate weighs 23 kg per square
        metre: no gripper pinches it). (Cloth is built as hinged links that drape.)"""
        if not self.is_thin_box:
            return False
        _, *face = sorted(self.size)
        return self.effective_mass <= SHEET_AREAL_DENSITY * face[0] * face[1]

    @property
    def is_thin_box(self) -> bool:
        """Whether it is a box at most :data:`SHEET_THICKNESS` thick: a sheet or a plate, as its mass decides."""
        return self.shape == "box" and min(self.size) <= SHEET_THICKNESS

    @property
    def grasp_point(self) -> tuple[float, float, float]:
        """Where the gripper holds it: as given, or the top centre of its bounding box."""
        if self.graspable_point is not None:
            return self.graspable_point
        x, y, z = self.center
        return (x, y, z + self.size[2] / 2)

    @property
    def top(self) -> float:
        """Height of the highest point of the object, m."""
        return float(max(p.aabb()[1][2] for p in geometry.object_parts(self)))

    @property
    def bottom(self) -> float:
        """Height of the lowest point of the object, m."""
        return float(min(p.aabb()[0][2] for p in geometry.object_parts(self)))
