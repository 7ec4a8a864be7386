"""The registry of robot types: what every part of robotool asks about a robot, in one record per robot.

A :class:`RobotType` holds everything that differs between embodiments: the limits model, the skills (the
sandbox, the describer, the argument checks and the signatures' validation all read this one list), the goal
kinds the robot supports, and its hooks grouped by who reads them: :class:`TaskRules` (task-file checks,
ground-truth key concepts), :class:`DescriptionHooks`, :class:`SimHooks` (embodiment: model building and skill
controller; goal trackers), its planner macros, :class:`FeedbackRules` (error classes) and :class:`PictureHooks`.
Nothing outside a robot's own package names a robot. Every registered robot must pass the conformance suite
(``tests/robots/test_conformance.py``); :func:`registered` registers robots for a block only (tests).

The built-in robots are registered when :mod:`robotool` is imported (its ``__init__``, the one place that lists
them). Robots from other packages are plug-ins, loaded on the first lookup:

- an entry point in the group ``robotool.robots`` (in the plug-in's ``pyproject.toml``:
  ``[project.entry-points."robotool.robots"] point = "my_package.point_robot:ROBOT"``);
- a module named in the environment variable ``ROBOTOOL_ROBOTS`` (comma-separated; processes started from this one
  inherit it) whose ``ROBOT`` attribute is a :class:`RobotType`;
- :func:`register` called by a program that embeds robotool.
"""

from __future__ import annotations

import difflib
import importlib
import os
import traceback
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import metadata
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from pydantic import BaseModel

from robotool.errors import RobotoolError
from robotool.robots import limits_table
from robotool.robots.skills import SceneBox, SkillArgumentError, SkillSpec, check_arguments

if TYPE_CHECKING:
    from robotool.planner.codegen import Program
    from robotool.rollout import EventKind, SkillCall
    from robotool.sim.embodiment import Embodiment, GoalTrackerFactory
    from robotool.task.key_concept import KeyConcept
    from robotool.task.scene import SceneObject
    from robotool.task.task_model import Task
    from robotool.task.task_problem import Problem

ENTRY_POINT_GROUP = "robotool.robots"
MODULES_VARIABLE = "ROBOTOOL_ROBOTS"


@dataclass(frozen=True)
class SearchMacros:
    """A robot's part of the LM-free search planner: its candidate programs and how much to verify."""

    candidates: Callable[[Task, bool], Iterator[Program]]
    """Candidate programs for a task (``tools=False``: without tools), shortest first."""
    beam: int
    """Programs per round (one simulator batch)."""
    rounds: int
    """Rounds at most."""
    work: float
    """World-seconds to simulate at most (the simulated seconds of every world run, and of each batch's longest
    world :data:`~robotool.planner.search.TICK_WEIGHT` times more): a round starts only when it is likely to end
    within them."""
    first: int | None = None
    """Programs in the first round (default ``beam``)."""
    doubted_rounds: int | None = None
    """Rounds at most while every program run was predicted to break a limit and none succeeded in any world (the
    programs are ordered, so the rest are doubted too); None: no such limit."""


@dataclass(frozen=True)
class PictureSettings:
    """How pictures look at the robot's scenes: camera degrees from the side view and down from level, and the
    side (m) of the floor's checker squares."""

    turn: float
    elevation: float
    floor_square: float


Reach = list[tuple[float, float, float]]
"""Points (m) a robot can reach."""
L = TypeVar("L", bound=BaseModel)
"""A robot's limits model: the hooks that take limits take this robot's own."""


def _no_problems(task: Task) -> list[Problem]:
    return []


def _no_facts(obj: SceneObject) -> list[str]:
    return []


def _no_hint(call: SkillCall) -> str | None:
    return None


def _no_reach(limits: BaseModel) -> Reach:
    return []


def _origin(task: Task) -> tuple[float, float]:
    return (0.0, 0.0)


def _marker(task: Task) -> tuple[float, float] | None:
    return None


@dataclass(frozen=True)
class TaskRules(Generic[L]):
    """What a task file may say about the robot, and what follows from it."""

    key_concepts: Callable[[Task], list[KeyConcept]]
    """The ground-truth quantities that decide whether the task needs a tool."""
    check_robot: Callable[[Task], list[Problem]] = _no_problems
    """Task-file problems with the robot's own keys (a start position it needs or cannot have)."""
    check_start: Callable[[Task], list[Problem]] = _no_problems
    """Task-file problems with where the robot starts in the scene (run once the scene's geometry is valid)."""
    planar: bool = False
    """Whether the motion skills ignore z, so a 2-D target ``[x, y]`` from a model is read as ``[x, y, 0]``."""
    reach: Callable[[L], Reach] = _no_reach
    """Points (m) the robot can reach beyond the scene's objects (a workspace's corners), for the box that
    position arguments are checked against."""


@dataclass(frozen=True)
class DescriptionHooks:
    """What the task's description (the text the LM stages read) says about the robot."""

    section: Callable[[Task], list[str]]
    """The description's robot section: what the robot is, where it starts, its limits in words."""
    ground: str = "the ground"
    """What z = 0 is."""
    object_facts: Callable[[SceneObject], list[str]] = _no_facts
    """Facts about an object that only this robot's skills use (for a gripper: its graspable point)."""


@dataclass(frozen=True)
class SimHooks(Generic[L]):
    """The robot in the simulator. Both import the simulator when called (it is heavy to import)."""

    embodiment: Callable[[L], Embodiment]
    """The simulator embodiment for a task's limits: model building and the skill controller."""
    goal_trackers: Callable[[], Mapping[str, GoalTrackerFactory]]
    """Trackers of the goal kinds only this robot has (the object goals are :mod:`robotool.sim.goals`')."""
    run_cost: float = 1.0
    """How long a run of this robot's task takes against others' (1: the default), so that a batch of runs
    starts the longest first (:func:`robotool.eval.sweep.longest_first`)."""


@dataclass(frozen=True)
class FeedbackRules:
    """How the robot's failures are classed and explained (error classes, optimiser feedback)."""

    numerical_events: frozenset[EventKind] = frozenset()
    """Events that make a failed call a numerical error (a target clamped to the workspace, a grasp that missed)."""
    placement_measures: frozenset[str] = frozenset()
    """Measured values of a refusal that a badly placed tool leaves (a step, gap or drop), for feedback."""
    numerical_hint: Callable[[SkillCall], str | None] = _no_hint
    """For a call that ended ``done`` in a world classed numerical: what went wrong, if this call shows it."""


@dataclass(frozen=True)
class PictureHooks:
    """How pictures show the robot's scenes and plans."""

    view: PictureSettings = PictureSettings(turn=-30.0, elevation=-30.0, floor_square=0.25)
    start_xy: Callable[[Task], tuple[float, float]] = _origin
    """Where the robot starts in x-y (m), for plans drawn from above."""
    footprint: Callable[[Task], tuple[float, float] | None] = _marker
    """The robot's x-y size (m) drawn at its start, or None for a marker."""


@dataclass(frozen=True)
class RobotType(Generic[L]):
    """One embodiment, as the rest of robotool sees it: its limits and skills, and its hooks grouped by who reads
    them (task rules, description, simulator, planner, feedback, pictures)."""

    name: str
    """The task file's ``robot.type``."""
    article: str
    """'a' or 'an', for sentences such as "a point cannot have a 'grasped' goal"."""
    limits: type[L]
    """The limits model; a task's ``robot.limits`` overrides its defaults."""
    skills: tuple[SkillSpec, ...]
    """The skills, in the order the description lists them."""
    goals: frozenset[str]
    """The goal kinds (keys of the task file's ``goal``) this robot can be given."""
    rules: TaskRules[L]
    description: DescriptionHooks
    sim: SimHooks[L]
    planner: Callable[[], SearchMacros] | None = None
    """The robot's search-planner macros, imported when called (None: the planner cannot solve its tasks)."""
    feedback: FeedbackRules = FeedbackRules()
    pictures: PictureHooks = PictureHooks()

    def skill(self, name: str) -> SkillSpec | None:
        """The skill called ``name``, or None."""
        return next((s for s in self.skills if s.name == name), None)

    @property
    def skill_names(self) -> frozenset[str]:
        """Names of the skills (the sandbox allowlist)."""
        return frozenset(s.name for s in self.skills)

    def check_call(self, name: str, args: tuple[object, ...], scene: SceneBox | None = None) -> tuple[object, ...]:
        """Check a call of skill ``name`` (:func:`~robotool.robots.skills.check_arguments`); an unknown skill is a
        :class:`~robotool.robots.skills.SkillArgumentError` that lists this robot's skills."""
        spec = self.skill(name)
        if spec is None:
            known = ", ".join(s.name for s in self.skills)
            raise SkillArgumentError(f"unknown skill {name!r} for the {self.name} (skills: {known})")
        return check_arguments(spec, args, scene)


class UnknownRobotError(RobotoolError, ValueError):
    """A robot type that is not registered; the message lists the registered ones."""


class RobotPluginError(RobotoolError):
    """A robot plug-in that cannot be loaded; the message names it and why."""


_ROBOTS: dict[str, RobotType[Any]] = {}
_LOADED: set[str] = set()  # sources already loaded: "entry points", and each module of the variable


def register(robot: RobotType[Any]) -> None:
    """Add a robot type; registering the same record again does nothing, another one under a taken name fails."""
    taken = _ROBOTS.get(robot.name)
    if taken is not None and taken is not robot:
        raise RobotPluginError(f"a robot named {robot.name!r} is already registered; choose another name")
    _ROBOTS[robot.name] = robot
    limits_table.add(robot.name, robot.limits)


@contextmanager
def registered(*robots: RobotType[Any], reload_plugins: bool = False) -> Iterator[None]:
    """Register ``robots`` for the block only: afterwards the registry (with its limits table and the plug-ins it
    has loaded) is as before. ``reload_plugins``: load the entry points and ``ROBOTOOL_ROBOTS`` again inside."""
    saved = dict(_ROBOTS), set(_LOADED), dict(limits_table.LIMITS_MODELS)
    if reload_plugins:
        _LOADED.clear()
    try:
        for robot in robots:
            register(robot)
        yield
    finally:
        _ROBOTS.clear()
        _ROBOTS.update(saved[0])
        _LOADED.clear()
        _LOADED.update(saved[1])
        limits_table.LIMITS_MODELS.clear()
        limits_table.LIMITS_MODELS.update(saved[2])


def get(name: str) -> RobotType[Any]:
    """The robot type called ``name`` (:class:`UnknownRobotError` naming the registered ones otherwise)."""
    _load()
    robot = _ROBOTS.get(name)
    if robot is None:
        raise UnknownRobotError(unknown_message(name))
    return robot


def names() -> tuple[str, ...]:
    """Names of every registered robot type, sorted."""
    _load()
    return tuple(sorted(_ROBOTS))


def robots() -> tuple[RobotType[Any], ...]:
    """Every registered robot type, by name."""
    _load()
    return tuple(_ROBOTS[n] for n in sorted(_ROBOTS))


def unknown_message(name: object) -> str:
    """``unknown robot type 'pont' (did you mean 'point'?); registered: ...``, with every registered name."""
    known = names()
    close = difflib.get_close_matches(str(name), known, n=1, cutoff=0.6) if isinstance(name, str) else []
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return f"unknown robot type {name!r}{hint}; registered: {', '.join(known)}"


def _load() -> None:
    """Register the entry points' robots and those of the modules in ``ROBOTOOL_ROBOTS`` (once each)."""
    if "entry points" not in _LOADED:
        _LOADED.add("entry points")
        for point in metadata.entry_points(group=ENTRY_POINT_GROUP):
            try:
                loaded = point.load()
            except Exception as e:
                raise _load_error(f"robot plug-in {point.value!r} (entry point {point.name!r})", e) from e
            _register_loaded(loaded, f"entry point {point.name!r}")
    for module_name in (m.strip() for m in os.environ.get(MODULES_VARIABLE, "").split(",")):
        if module_name and module_name not in _LOADED:
            _LOADED.add(module_name)
            try:
                module = importlib.import_module(module_name)
            except Exception as e:
                _LOADED.discard(module_name)
                raise _load_error(f"robot module {module_name!r} (from {MODULES_VARIABLE})", e) from e
            _register_loaded(module, f"module {module_name!r}")


def _load_error(plugin: str, error: Exception) -> RobotPluginError:
    """The error for a plug-in whose import raised ``error``: it names the plug-in, the error and the line of the
    plug-in's code that raised it (the cause stays chained, with its traceback)."""
    frames = [f for f in traceback.extract_tb(error.__traceback__) if not f.filename.startswith("<")]
    machinery = (os.path.dirname(importlib.__file__), os.path.abspath(__file__))  # the import's frames, and ours
    own = [f for f in frames if not os.path.abspath(f.filename).startswith(machinery)]
    where = f" (at {own[-1].filename}, line {own[-1].lineno})" if own else ""
    return RobotPluginError(f"cannot load {plugin}: {type(error).__name__}: {error}{where}")


def _register_loaded(loaded: object, source: str) -> None:
    robot = loaded if isinstance(loaded, RobotType) else getattr(loaded, "ROBOT", None)
    if not isinstance(robot, RobotType):
        raise RobotPluginError(f"robot plug-in {source} gives no RobotType (a module needs a ROBOT attribute)")
    register(robot)
