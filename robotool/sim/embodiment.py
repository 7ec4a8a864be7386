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
   An exception inside the controller fails only the world it belongs to: ``start`` and ``query`` run per world;
   per-world work inside ``tick`` that cannot be undone (advancing a plan) ends that world's skill with outcome
   ``error`` (:func:`error_end`) instead of raising; and when ``tick`` raises anyway, the runner restores the
   controller's per-world state (its numpy-array and list attributes, the controls and the welds) as it was
   before the tick and ticks the worlds one by one, failing those that raise again. A controller therefore keeps
   its per-world state in numpy arrays and lists indexed by world, and ``tick(state, worlds)`` touches only
   ``worlds``.
3. **Goals.** Goal sub-conditions are evaluated by :mod:`robotool.sim.goals` from the batched state;
   a robot's own goal kinds are trackers in its package (``RobotType.sim.goal_trackers``).

All arrays carry the world index first, ``(nworld, ...)``; lengths are metres, times seconds.
:func:`robotool.sim.build.embodiment_for` asks the robot registry for ``task.robot.type``'s embodiment.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol

import numpy as np

from robotool.task import geometry

if TYPE_CHECKING:
    import mujoco

    from robotool.rollout import Event
    from robotool.sim.backend import BatchedSim, BatchState
    from robotool.sim.compiled_scene import Scene
    from robotool.task.task_model import Task

EndOutcome = Literal["done", "stalled", "timeout", "refused", "fell", "error"]


@dataclass(frozen=True)
class SkillEnd:
    """A motion skill that finished in one world: how, why, the values behind it and what happened.

    ``events`` are typed records of what happened during the skill (a clamp, a grasp that held nothing,
    an object pushed away); the runner stamps them with the call and the time.
    """

    world: int
    outcome: EndOutcome  # "error": the controller raised while running the skill; the runner fails the world
    reason: str | None = None
    measured: dict[str, float] = field(default_factory=dict)
    result: Any = None
    events: tuple[Event, ...] = ()


class QueryError(ValueError):
    """A query skill cannot be answered (e.g. an unknown object); the program sees the message."""


class SkillController(Protocol):
    """Runs one embodiment's skills in every world of one batched simulator."""

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin motion skill ``skill`` (arguments already checked by ``check_call``) in ``worlds``.

        Returns the worlds where the skill ends at once (e.g. refused before moving); the others
        are reported later by :meth:`tick`.
        """

    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        """One control tick in ``worlds`` (all when None; the others are left untouched): report finished skills,
        then write controls for the next interval."""

    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        """Answer a query skill in one world from the current state (raise :class:`QueryError`)."""


def describe_error(error: Exception) -> str:
    """An exception raised inside a controller as one line: its type and message."""
    return " ".join(f"{type(error).__name__}: {error}".split())[:400]


def error_end(world: int, error: Exception) -> SkillEnd:
    """The end of a skill whose controller raised ``error`` in ``world`` (the runner fails that world only)."""
    return SkillEnd(world=world, outcome="error", reason=describe_error(error))


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


def controller_conditions(controller: SkillController) -> dict[str, list[bool]]:
    """Conditions on the robot itself that every goal gains, per world (such as ``robot_has_not_fallen``), from the
    controller's ``robot_conditions()`` method; none for a controller without one (a robot that cannot fall)."""
    conditions = getattr(controller, "robot_conditions", None)
    return {} if conditions is None else conditions()


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

    def update(self, state: BatchState, active: np.ndarray) -> None:
        """Observe the state of the ``active`` worlds after a control tick."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        """Named sub-conditions now, each (nworld,) bool."""
