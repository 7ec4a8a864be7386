"""The embodiment-controller interface that every robot implements (``RobotType.sim.embodiment``).

An embodiment takes part in three phases, and only talks to the simulator through the
backend-agnostic :class:`~robotool.sim.backend.BatchedSim` (never backend internals):

1. **Model building.** :meth:`Embodiment.add_to_spec` adds the robot's bodies, joints, actuators,
   sensors and equalities to the ``mujoco.MjSpec`` that :func:`robotool.sim.build` made from the task.
   Robot element names start with ``robot`` so they never clash with task objects (which may not be
   named ``robot``). Objects are already in the spec as bodies named after the task objects.
2. **Running skills.** :meth:`Embodiment.controller` returns a :class:`SkillController` bound to one
   batched simulator. The runner calls :meth:`SkillController.start` when programs in some worlds call a
   motion skill, then, at every control tick (every ``Scene.control_substeps`` physics steps), calls
   :meth:`SkillController.tick` with a fresh :class:`~robotool.sim.backend.BatchState`. ``tick`` reports
   the skills that finished since the last tick (:class:`SkillEnd`, with outcome ``done``, ``stalled``,
   ``timeout``, ``refused`` or ``fell``, a reason and measured values) and writes the controls for the next
   interval through the simulator: ``sim.ctrl`` / ``sim.mocap_pos`` (numpy buffers, world first,
   pushed to the backend before each step), ``sim.set_weld(worlds, eq, active)`` (attach at the current
   relative pose, or detach) and ``sim.rays(...)`` for support heights.
   Query skills are answered at once by :meth:`SkillController.query` from the current state.
   An exception inside the controller is a bug in robotool, not the program's failure: it ends only the world it
   belongs to, as an internal error (logged with its traceback, recorded in the rollout's ``internal_error``);
   ``start`` and ``query`` run per world;
   per-world work inside ``tick`` that cannot be undone (advancing a plan) ends that world's skill with outcome
   ``internal_error`` (:func:`error_end`) instead of raising; and when ``tick`` raises anyway, the runner puts back the
   controller's :meth:`SkillController.snapshot` taken before the tick (:meth:`SkillController.restore`), the
   controls and the welds, and ticks the worlds one by one, failing those that raise again. A controller therefore
   keeps all its per-world state in the dataclasses that :meth:`SkillController.world_states` returns (one per
   component, arrays and lists indexed by world first), and ``tick(state, worlds)`` touches only ``worlds``.
3. **Goals.** Goal sub-conditions are evaluated by :mod:`robotool.sim.goals` from the batched state;
   a robot's own goal kinds are trackers in its package (``RobotType.sim.goal_trackers``).

All arrays carry the world index first, ``(nworld, ...)``; lengths are metres, times seconds.
:func:`robotool.sim.build.embodiment_for` asks the robot registry for ``task.robot.type``'s embodiment.
"""

from __future__ import annotations

import copy
import functools
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, fields, is_dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from robotool.bugs import describe
from robotool.task import geometry
from robotool.vocabulary import SkillOutcome

if TYPE_CHECKING:
    import mujoco

    from robotool.rollout import Event
    from robotool.sim.backend import BatchedSim, BatchState
    from robotool.sim.compiled_scene import Scene
    from robotool.task.task_model import Task


@dataclass(frozen=True)
class SkillEnd:
    """A motion skill that finished in one world: how, why, the values behind it and what happened.

    ``events`` are typed records of what happened during the skill (a clamp, a grasp that held nothing,
    an object pushed away); the runner stamps them with the call and the time.
    """

    world: int
    outcome: SkillOutcome  # "internal_error": the controller raised while running the skill (a bug in robotool)
    reason: str | None = None
    measured: dict[str, float] = field(default_factory=dict)
    result: Any = None
    events: tuple[Event, ...] = ()
    error: BaseException | None = field(default=None, compare=False)  # what the controller raised (internal_error)


class QueryError(ValueError):
    """A query skill cannot be answered (e.g. an unknown object); the program sees the message."""


class SkillController(ABC):
    """Runs one embodiment's skills in every world of one batched simulator.

    The contract: :meth:`start`, :meth:`tick` and :meth:`query` run the skills; :meth:`world_states` names the
    dataclasses that hold all the controller's per-world state (world index first), which :meth:`snapshot` copies
    and :meth:`restore` puts back (the runner's undo of a batched tick that raised); :meth:`robot_conditions` and
    :meth:`overloaded` are optional hooks with defaults (no conditions on the robot itself, nothing overloaded).
    """

    @abstractmethod
    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin motion skill ``skill`` (arguments already checked by ``check_call``) in ``worlds``.

        Returns the worlds where the skill ends at once (e.g. refused before moving); the others
        are reported later by :meth:`tick`.
        """

    @abstractmethod
    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        """One control tick in ``worlds`` (all when None; the others are left untouched): report finished skills,
        then write controls for the next interval."""

    @abstractmethod
    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        """Answer a query skill in one world from the current state (raise :class:`QueryError`)."""

    @abstractmethod
    def world_states(self) -> tuple[Any, ...]:
        """Every component's per-world state: one dataclass instance each (numpy arrays with the world index first,
        lists indexed by world), the same instances for the controller's lifetime. Nothing else a tick changes may
        live on the controller or its components."""

    def snapshot(self) -> ControllerSnapshot:
        """A copy of the per-world state (:meth:`world_states`), to :meth:`restore` later."""
        return ControllerSnapshot(tuple(copy_state(s) for s in self.world_states()))

    def restore(self, snapshot: ControllerSnapshot) -> None:
        """Put the per-world state back as it was at ``snapshot`` (in place: components keep their references)."""
        live = self.world_states()
        if len(live) != len(snapshot.states):
            raise ValueError(f"a snapshot of {len(snapshot.states)} states for a controller with {len(live)}")
        for state, saved in zip(live, snapshot.states, strict=True):
            copy_state(saved, into=state)

    def robot_conditions(self, state: BatchState, worlds: list[int]) -> dict[str, list[bool]]:
        """Conditions on the robot itself that every goal gains, per world (such as ``robot_has_not_fallen``), as the
        goal of ``worlds`` (settled at ``state``) is read; none by default (a robot that cannot fall)."""
        return {}

    def robot_events(self, world: int) -> list[Event]:
        """What the robot's conditions saw happen in one world as its goal was read (none by default)."""
        return []

    def overloaded(self, state: BatchState) -> np.ndarray:
        """(nworld,) bool: the worlds in which ``state`` has the robot bear more than its contacts hold (a grip loaded
        past what its friction holds, which slips): what the world shows there did not happen, so goal memory skips it
        (a button pressed only by a tool the grip could not have held). None by default; read only."""
        return np.zeros(len(state.time), dtype=bool)


@dataclass(frozen=True)
class ControllerSnapshot:
    """A controller's per-world state at one moment (opaque: only :meth:`SkillController.restore` reads it)."""

    states: tuple[Any, ...]


def copy_state(state: Any, into: Any = None) -> Any:
    """A copy of the dataclass ``state`` whose arrays, lists and dicts (nested ones too) are copies; other values
    (numbers, strings, frozen records, plan generators) are shared. With ``into`` (a dataclass of the same type),
    the copied values are written into it instead, and it is returned."""
    if not is_dataclass(state) or isinstance(state, type):
        raise TypeError(f"per-world state must be a dataclass instance, not {type(state).__name__}")
    out = copy.copy(state) if into is None else into
    if type(out) is not type(state):
        raise TypeError(f"cannot copy a {type(state).__name__} into a {type(out).__name__}")
    for name in _field_names(type(state)):
        object.__setattr__(out, name, _copied(getattr(state, name)))
    return out


@functools.cache
def _field_names(kind: type) -> tuple[str, ...]:
    """The names of a dataclass's fields."""
    return tuple(f.name for f in fields(kind))


_CONTAINERS = (np.ndarray, list, dict)  # what a copy copies (anything else is shared)


def _copied(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, list):
        return [_copied(v) for v in value] if _nested(value) else value.copy()
    if isinstance(value, dict):
        return {k: _copied(v) for k, v in value.items()} if _nested(value.values()) else value.copy()
    return value


def _nested(values: Iterable[Any]) -> bool:
    """Whether any of ``values`` is an array, list or dict (which a copy copies in turn)."""
    return any(issubclass(kind, _CONTAINERS) for kind in set(map(type, values)))


def error_end(world: int, error: Exception) -> SkillEnd:
    """The end of a skill whose controller raised ``error`` in ``world``: an internal error, which ends that world
    only (the runner logs the traceback and records it apart from the program's failures)."""
    return SkillEnd(world=world, outcome="internal_error", reason=describe(error), error=error)


def world_mask(nworld: int, worlds: np.ndarray | None) -> np.ndarray:
    """(nworld,) True for the worlds in ``worlds`` (every world when None)."""
    mask = np.zeros(nworld, dtype=bool)
    mask[slice(None) if worlds is None else np.asarray(worlds, dtype=int)] = True
    return mask


def size_now(scene: Scene, state: BatchState, world: int, index: int) -> list[float]:
    """``get_size`` of a task object in one world: its size along x, y, z as it is turned now (see
    :func:`robotool.task.geometry.axis_aligned_size`); a cloth, which drapes, keeps its laid-out size."""
    obj = scene.task.objects[index]
    turned = geometry.rotation_matrix(obj.rpy) if obj.shape == "cloth" else state.xmat(scene.object_body[index])[world]
    return [float(v) for v in geometry.axis_aligned_size(obj.size, turned)]


def goal_events(goal: GoalTracker, world: int) -> list[Event]:
    """What the goal saw happen in one world (such as a fragile object breaking), from the tracker's
    ``events(world)`` method; none for a tracker without one."""
    events = getattr(goal, "events", None)
    return [] if events is None else events(world)


class Embodiment(Protocol):
    """One robot type: how it enters the model and how its skills run."""

    control_substeps: int
    """Physics steps per control tick (the controller's rate)."""

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Add the robot's bodies, actuators, sensors and equalities to the task's spec."""

    def controller(self, sim: BatchedSim) -> SkillController:
        """A controller for every world of ``sim`` (built from the scene this embodiment made)."""


class GoalTracker(Protocol):
    """Follows one goal in every world."""

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        """Observe the state of the ``active`` worlds after a control tick (or a physics step, where watched).
        ``credited`` (within ``active``): the worlds whose state may count toward the goal, not those where the robot
        bears more than its contacts hold (what they show did not happen); what breaks counts in every active world."""

    def watched(self, state: BatchState) -> np.ndarray:
        """(nworld,) bool: the worlds whose next control interval must be seen at every physics step (:meth:`update`
        after each), because what the goal reads may happen and be over between two ticks there."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        """Named sub-conditions now, each (nworld,) bool."""


class ReadAtTicks:
    """For a :class:`GoalTracker` that reads the world at control ticks only: no world is ever watched."""

    def watched(self, state: BatchState) -> np.ndarray:
        """No world: what this goal reads lasts from one tick to the next."""
        return np.zeros(len(state.time), dtype=bool)


GoalTrackerFactory = Callable[["Scene", "BatchedSim"], GoalTracker]
"""Makes a robot's goal tracker for a scene and the simulator that runs it (to read what the batched state does not
hold, such as which way touching bodies press on each other)."""
