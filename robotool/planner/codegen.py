"""Candidate programs as they are built: skill calls as program text, plan steps and their parameters.

A :class:`Program` collects the lines of a skill program (the form the sandbox accepts: skills called
as plain functions, no imports beyond numpy/math, no definitions) together with one typed
:class:`~robotool.signatures.models.PlanStep` and :class:`~robotool.signatures.models.StepParameters`
per motion skill. Positions that depend on where objects are when the step runs are written as
:class:`Point` values: per axis, a number or a queried position (:class:`Ref`) plus an offset, and, where a
target lies along a line between two objects as they lie then, a distance along a :class:`Direction`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from robotool.signatures.models import PlanStep, StepParameters


@dataclass(frozen=True)
class Ref:
    """A position the program queries when it runs: variable ``var`` holds ``skill(obj)``.

    ``value`` is the plan-time estimate (from the task file), used for the step parameters.
    """

    var: str
    obj: str
    skill: str
    value: tuple[float, float, float]


Axis = tuple[Ref | None, float]


def _three(axes: Sequence[Axis]) -> tuple[Axis, Axis, Axis]:
    """``axes`` as x, y and z (a ValueError unless there are three)."""
    x, y, z = axes
    return x, y, z


@dataclass(frozen=True)
class Direction:
    """A unit x-y direction the program computes when it runs, from one queried position toward another: ``var``
    holds the difference and ``norm`` its length. ``value`` is the plan-time estimate."""

    var: str
    norm: str
    value: tuple[float, float]


@dataclass(frozen=True)
class Point:
    """A 3-D target: per axis, ``ref[axis] + offset`` (or the number alone when ``ref`` is None), plus, when
    ``along`` is given, ``distance`` times a :class:`Direction` in x and y."""

    axes: tuple[Axis, Axis, Axis]
    along: tuple[Direction, float] | None = None

    @classmethod
    def at(cls, ref: Ref | None, offset: Sequence[float] = (0.0, 0.0, 0.0)) -> Point:
        """``ref`` plus ``offset`` on every axis (absolute numbers when ``ref`` is None)."""
        return cls(_three([(ref, float(o)) for o in offset]))

    def with_axis(self, k: int, ref: Ref | None, offset: float) -> Point:
        """This point with axis ``k`` replaced."""
        axes = list(self.axes)
        axes[k] = (ref, float(offset))
        return Point(_three(axes), self.along)

    def shifted(self, delta: Sequence[float]) -> Point:
        """This point moved by ``delta``."""
        return Point(_three([(r, o + float(d)) for (r, o), d in zip(self.axes, delta, strict=True)]), self.along)

    def estimate(self) -> np.ndarray:
        """Plan-time value of the point."""
        point = np.array([(r.value[k] if r else 0.0) + o for k, (r, o) in enumerate(self.axes)])
        if self.along is not None:
            direction, distance = self.along
            point[:2] += distance * np.array(direction.value)
        return point

    def code(self) -> str:
        """The point as a Python list expression."""
        axes = [_axis_code(r, o, k) for k, (r, o) in enumerate(self.axes)]
        if self.along is not None:
            direction, distance = self.along
            sign = "+" if distance >= 0 else "-"
            for k in (0, 1):
                axes[k] += f" {sign} {abs(distance):.4f} * {direction.var}[{k}] / {direction.norm}"
        return "[" + ", ".join(axes) + "]"

    def parameters(self, step: int, obj: str | None, explanation: str) -> StepParameters:
        """Typed parameters: an offset from one object's centre when that is what it is, else a target."""
        refs = {r for r, _ in self.axes}
        offset = [round(o, 4) for _, o in self.axes]
        simple = len(refs) == 1 and self.along is None
        if simple and (ref := next(iter(refs))) is not None and ref.skill in ("get_center", "get_position"):
            return StepParameters(step=step, object=obj, relative_to=ref.obj, offset=offset, explanation=explanation)
        return StepParameters(
            step=step,
            object=obj,
            target=[round(float(v), 4) for v in self.estimate()],
            explanation=f"{explanation}; computed when the step runs as {self.code()}",
        )


def _axis_code(ref: Ref | None, offset: float, k: int) -> str:
    if ref is None:
        return f"{offset:.4f}"
    if abs(offset) < 5e-5:
        return f"{ref.var}[{k}]"
    sign = "+" if offset > 0 else "-"
    return f"{ref.var}[{k}] {sign} {abs(offset):.4f}"


@dataclass(frozen=True)
class Motion:
    """Where a motion call is in a program: its line, skill, object, target and plan step (from 1)."""

    line: int
    skill: str
    obj: str | None
    point: Point | None
    step: int
    explanation: str


def _call(skill: str, obj: str | None, point: Point | None) -> str:
    args = ([repr(obj)] if obj is not None else []) + ([point.code()] if point is not None else [])
    return f"{skill}({', '.join(args)})"


@dataclass
class Program:
    """A candidate program under construction, with its plan steps, parameters and the objects it uses."""

    lines: list[str] = field(default_factory=list)
    steps: list[PlanStep] = field(default_factory=list)
    parameters: list[StepParameters] = field(default_factory=list)
    motions: list[Motion] = field(default_factory=list)
    objects: list[str] = field(default_factory=list)
    sentences: list[str] = field(default_factory=list)
    roles: dict[str, str] = field(default_factory=dict)
    doubt: str | None = None  # a limit the planner predicts the program breaks, if any
    late: int = 0  # how many less likely choices it makes (tried after programs with fewer)
    slack: float = float("inf")  # m its tightest stance keeps from an edge it must stay within (less: tried later)
    thin: list[str] = field(default_factory=list)  # other margins it leaves too thin for some perturbed worlds
    calls: list[int] = field(default_factory=list)  # the line of each skill call (queries too), in the order they run
    _count: int = 0

    def use(self, name: str, role: str | None = None) -> None:
        """Record that the program uses object ``name`` (with its role, if it has one)."""
        if name not in self.objects:
            self.objects.append(name)
        if role and name not in self.roles:
            self.roles[name] = role

    def say(self, sentence: str) -> None:
        """Add one sentence to the program's abstract plan."""
        self.sentences.append(sentence)

    def query(self, skill: str, obj: str, value: Sequence[float]) -> Ref:
        """Query a position now (``var = skill('obj')``) and return it as a :class:`Ref`."""
        self._count += 1
        ref = Ref(f"p{self._count}", obj, skill, (float(value[0]), float(value[1]), float(value[2])))
        self.lines.append(f"{ref.var} = {skill}({obj!r})")
        self.calls.append(len(self.lines) - 1)
        return ref

    def direction(self, start: Ref, end: Ref) -> Direction:
        """The unit x-y direction from ``start``'s position toward ``end``'s, computed when the program runs."""
        self._count += 1
        var, norm = f"d{self._count}", f"n{self._count}"
        self.lines.append(f"{var} = [{end.var}[0] - {start.var}[0], {end.var}[1] - {start.var}[1]]")
        self.lines.append(f"{norm} = ({var}[0] ** 2 + {var}[1] ** 2) ** 0.5")
        planned = np.array(end.value[:2]) - np.array(start.value[:2])
        unit = planned / max(float(np.linalg.norm(planned)), 1e-9)
        return Direction(var, norm, (float(unit[0]), float(unit[1])))

    def motion(
        self,
        skill: str,
        *,
        point: Point | None = None,
        obj: str | None = None,
        objects: Sequence[str] = (),
        intent: str,
        explanation: str = "",
    ) -> None:
        """Call a motion skill; record its plan step and, for a position, its parameters."""
        self.lines.append(_call(skill, obj, point))
        self.calls.append(len(self.lines) - 1)
        names = list(dict.fromkeys([*([obj] if obj else []), *objects]))
        self.steps.append(PlanStep(skill=skill, objects=names, intent=intent))
        self.motions.append(Motion(len(self.lines) - 1, skill, obj, point, len(self.steps), explanation or intent))
        if point is not None:
            self.parameters.append(point.parameters(len(self.steps), obj, explanation or intent))

    def turn(self, heading: int, intent: str) -> None:
        """Turn in place to ``heading`` (degrees); a plan step without parameters."""
        self.lines.append(f"turn_to_heading({heading})")
        self.calls.append(len(self.lines) - 1)
        self.steps.append(PlanStep(skill="turn_to_heading", objects=[], intent=intent))
        self.motions.append(Motion(len(self.lines) - 1, "turn_to_heading", None, None, len(self.steps), intent))
        self.say(f"Turn in place to a heading of {heading} degrees.")

    def with_target_shifted(self, motion: int, delta: Sequence[float], why: str) -> Program:
        """A copy whose ``motion``-th motion call (from 0) aims ``delta`` further; ``why`` joins the plan."""
        move = self.motions[motion]
        if move.point is None:
            raise ValueError(f"motion {motion} ({move.skill}) has no target to shift")
        point = move.point.shifted(delta)
        moved = replace(move, point=point)
        copy = replace(
            self,
            lines=list(self.lines),
            calls=list(self.calls),
            motions=list(self.motions),
            sentences=[*self.sentences, why],
            parameters=[
                point.parameters(p.step, move.obj, f"{move.explanation}; {why}") if p.step == move.step else p
                for p in self.parameters
            ],
        )
        copy.lines[move.line] = _call(move.skill, move.obj, point)
        copy.motions[motion] = moved
        return copy

    @property
    def code(self) -> str:
        """The program text."""
        return "\n".join(self.lines) + "\n"

    def reaching_call(self, k: int, *, whole: bool) -> str | None:
        """The program text up to its ``k``-th skill call (from 0; None past its last), and that call: ``whole``, or
        as far as its object (whole when it has none). A program whose text starts with it makes the same calls as this
        one before that call, with the same arguments, in a world made from the same seed, and then that call (or the
        same skill on the same object, its target perhaps another)."""
        if not 0 <= k < len(self.calls):
            return None
        line = self.calls[k]
        before = "".join(f"{text}\n" for text in self.lines[:line])
        motion = next((m for m in self.motions if m.line == line), None)
        if not whole and motion is not None and motion.obj is not None:
            return before + f"{motion.skill}({motion.obj!r}"
        return before + self.lines[line] + "\n"

    @property
    def abstract_plan(self) -> str:
        """The plan in words."""
        return " ".join(self.sentences)
