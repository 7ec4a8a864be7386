"""The lockstep runner: N programs in N perturbed worlds of one task, stepped together.

Each program runs until it calls a motion skill or ends; query skills are answered at once from the current state; the
batch then steps, one control tick at a time, until the pending motion skills finish (done, stalled, timeout, refused,
fell), and the programs whose skill finished are resumed. The runner resumes every such world first and only then waits
on each (so sandboxed programs run in parallel). A program that errors or ends is finished for its world only; its
world then runs on with the robot holding still for at least ``SETTLE_AFTER`` simulated seconds and until every object
lies still and is not speeding up (what rocks, rolls or tips comes to rest, a falling object lands, a bottle that
starts to roll down a gentle slope rolls on) before the goal is read; a world still
moving ``SETTLE_LONGEST`` seconds after its program ended fails, naming what moves (a goal is never read from a world
in motion). Skill arguments are checked on this side of the sandbox, positions against the scene's box
(:func:`scene_box`). An exception inside the skill controller is a bug in robotool: it is logged with its traceback and
ends the world it happened in as an internal error (the rollout's ``internal_error``, kept apart from the program's
failures), never the batch: when the batched control tick raises, the controller's per-world state is put back as it
was before the tick and the worlds are ticked one by one. Each world yields a :class:`~robotool.rollout.Rollout`.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from robotool import robots
from robotool.bugs import InternalError
from robotool.program_session import (
    ProgramEnded,
    ProgramSession,
    SkillReply,
    SkillRequest,
    TrustedProgram,
    TrustedSession,
    wait_all,
)
from robotool.robots.skills import SceneBox, SkillArgumentError
from robotool.rollout import Event, Rollout, SkillCall
from robotool.safe_text import capped, one_line
from robotool.sim.backend import BatchedSim, BatchState, Perturbation
from robotool.sim.backend_choice import make_sim
from robotool.sim.build import build, embodiment_for
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import (
    GoalTracker,
    QueryError,
    SkillController,
    SkillEnd,
    goal_events,
)
from robotool.sim.goals import goal_tracker
from robotool.sim.magnets import Magnets
from robotool.sim.recorder import StateRecorder
from robotool.sim.sheets import Sheets
from robotool.task import geometry
from robotool.task.task_model import Task
from robotool.vocabulary import BackendName

SETTLE_TIME = 0.3  # s of physics before the programs start
SETTLE_AFTER = 1.0  # s of physics after a program ends, at least, before its goal is read
SETTLE_LONGEST = 5.0  # s after a program ends by which every object must lie still, or its world fails
STILL_SPEED = 0.02  # m/s: an object whose bodies all move slower than this lies still
SPEEDING_UP = 0.0005  # m: a body that moved this much farther in the later half of its settling than in the earlier
# half is speeding up (a bottle starting to roll down a gentle slope), however slowly it moves: not lying still
MAX_SIM_TIME = 120.0  # s of simulated time a whole rollout may take
MAX_SKILL_CALLS = 200  # skill calls (queries included) a whole rollout may make
MOVED = 0.01  # m: an object displaced this much counts as touched

logger = logging.getLogger(__name__)


@dataclass
class _World:
    """The runner's bookkeeping for one world."""

    session: ProgramSession
    calls: list[SkillCall] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    pending: SkillCall | None = None
    pending_args: tuple[Any, ...] = ()
    ended: bool = False
    settle_until: float = np.inf  # simulated time when the ended world's goal is read
    settling: list[np.ndarray] = field(default_factory=list)  # the objects' bodies' positions at each settling tick
    finished: bool = False
    error: str | None = None
    internal_error: InternalError | None = None
    output: str = ""
    conditions: dict[str, bool] = field(default_factory=dict)
    sim_time: float = 0.0


def _speeding_up(positions: list[np.ndarray]) -> bool:
    """Whether a body moved :data:`SPEEDING_UP` farther in the later half of ``positions`` (its bodies' positions
    (nbody, 3) at each tick) than in the earlier half."""
    half = (len(positions) - 1) // 2
    if half < 1:
        return False
    later = np.linalg.norm(positions[-1] - positions[-1 - half], axis=1)
    earlier = np.linalg.norm(positions[-1 - half] - positions[-1 - 2 * half], axis=1)
    return bool(np.any(later > earlier + SPEEDING_UP))


def trusted_sessions(task: Task, programs: Sequence[TrustedProgram]) -> list[TrustedSession]:
    """One :class:`~robotool.program_session.TrustedSession` per trusted callable ``program(robot)``."""
    names = robots.get(task.robot.type).skill_names
    return [TrustedSession(p, names) for p in programs]


def run_sessions(
    task: Task | Scene,
    sessions: Sequence[ProgramSession],
    *,
    seed: int = 0,
    world_seeds: Sequence[int] | None = None,
    backend: BackendName = "mujoco",
    perturb: bool = True,
    njmax: int | None = None,
    nconmax: int | None = None,
    max_sim_time: float = MAX_SIM_TIME,
    max_skill_calls: int = MAX_SKILL_CALLS,
    recorder: StateRecorder | None = None,
) -> list[Rollout]:
    """Run one program session per world and return one :class:`~robotool.rollout.Rollout` each.

    ``task`` may be a :class:`Task` or an already built :class:`~robotool.sim.compiled_scene.Scene` (to reuse
    the model). World ``w`` is perturbed from ``seed`` (friction, mass, small pose noise) unless
    ``perturb`` is False; with ``world_seeds``, world ``w`` is perturbed from ``world_seeds[w]`` alone,
    so candidates compared in one batch meet the same worlds. ``njmax``/``nconmax`` override the per-world
    constraint and contact capacity; a world that overflows them, diverges, runs over ``max_sim_time`` simulated seconds
    or makes more than ``max_skill_calls`` calls fails with that reason. A world succeeds when every
    goal sub-condition holds at its end and it has no error. The same inputs and seed give
    identical rollouts on the ``mujoco`` backend. Sessions are closed on return. A ``recorder`` keeps the
    states of the worlds it names at every control tick (for videos); without one nothing is kept.
    """
    scene = task if isinstance(task, Scene) else build(task)
    nworld = len(sessions)
    if not perturb:
        perturbation = Perturbation.none(scene, nworld)
    elif world_seeds is not None:
        if len(world_seeds) != nworld:
            raise ValueError(f"{len(world_seeds)} world seeds for {nworld} sessions")
        perturbation = Perturbation.for_seeds(scene, world_seeds)
    else:
        perturbation = Perturbation.sample(scene, nworld, seed)
    sim = make_sim(scene, nworld, backend=backend, perturbation=perturbation, njmax=njmax, nconmax=nconmax)
    try:
        seeds = list(world_seeds) if world_seeds is not None else [seed] * nworld
        return _Run(scene, sim, sessions, max_sim_time, max_skill_calls, recorder).run(seeds)
    finally:
        for s in sessions:
            s.close()
        close = getattr(sim, "close", None)
        if close is not None:
            close()


def run_programs(task: Task | Scene, programs: Sequence[TrustedProgram], **kwargs: Any) -> list[Rollout]:
    """:func:`run_sessions` for trusted callables (tests, hand-written programs)."""
    scene_task = task.task if isinstance(task, Scene) else task
    return run_sessions(task, trusted_sessions(scene_task, programs), **kwargs)


class _Run:
    """One lockstep run; see :func:`run_sessions`."""

    def __init__(
        self,
        scene: Scene,
        sim: BatchedSim,
        sessions: Sequence[ProgramSession],
        max_sim_time: float,
        max_skill_calls: int,
        recorder: StateRecorder | None = None,
    ):
        self.scene, self.sim, self.recorder = scene, sim, recorder
        self.max_sim_time, self.max_skill_calls = max_sim_time, max_skill_calls
        self.worlds = [_World(s) for s in sessions]
        self.robot = robots.get(scene.task.robot.type)
        self.kinds = {s.name: s.kind for s in self.robot.skills}
        self.box = scene_box(scene.task)
        self.controller: SkillController = embodiment_for(scene.task).controller(sim)
        self.magnets = Magnets(scene)
        self.sheets = Sheets(scene, sim.nworld)
        self.goal: GoalTracker = goal_tracker(scene, sim)
        nworld, nobj = sim.nworld, len(scene.object_names)
        self.touched = np.zeros((nworld, nobj), dtype=bool)
        self.object_bodies = np.flatnonzero(scene.body_object >= 0)
        self.robot_welds = _robot_welds(scene)
        self.start_xpos = np.zeros(0)
        self.t0 = np.zeros(nworld)

    def alive(self) -> np.ndarray:
        """Worlds still stepped: running a program, or settling after it."""
        return np.array([not w.finished for w in self.worlds])

    def running(self) -> np.ndarray:
        """Worlds whose program has not ended."""
        return np.array([not w.ended for w in self.worlds])

    def run(self, seeds: Sequence[int]) -> list[Rollout]:
        nworld = self.sim.nworld
        self.sim.step(max(1, round(SETTLE_TIME / self.scene.model.opt.timestep)), np.ones(nworld, dtype=bool))
        state = self.sim.state()
        self.t0 = state.time.copy()
        self.start_xpos = state.xpos.copy()
        if self.recorder is not None:
            self.recorder.start(state, self.sim.mocap_pos)
        for w in self.worlds:
            w.session.resume(None)
        self._collect(state, list(range(nworld)))
        while self.alive().any():
            self._step(state)
            previous, state = state, self.sim.state()
            if self.recorder is not None:
                self.recorder.capture(state, self.sim.mocap_pos)
            self._observe(state)
            self._finish_settled(state, previous)
            ends = self._tick(state)
            if ends:  # a finished skill may have changed the state (a grasp weld): programs see the new one
                state = self.sim.state()
            resumed = self._finish_skills(state, ends)
            self._collect(state, resumed)
        return [self._rollout(i, w, seeds[i]) for i, w in enumerate(self.worlds)]

    def _step(self, state: BatchState) -> None:
        """One control interval of physics in the alive worlds. Where the goal watches a world at ``state`` (a fragile
        object falling far enough to break), the interval is stepped one physics step at a time (every alive world:
        a batch may step all its worlds together) and the goal is updated after each in the watched worlds: the same
        physics (the controls hold through the interval), with nothing the goal reads left unseen between ticks."""
        alive, substeps = self.alive(), self.scene.control_substeps
        watched = alive & self.goal.watched(state)
        if not watched.any():
            self.sim.step(substeps, alive)
            return
        for k in range(substeps):
            self.sim.step(1, alive)
            if k < substeps - 1:  # (the interval's last state is the tick's, which the goal reads in _observe)
                inside = self.sim.state()
                self.goal.update(inside, watched, watched & ~self.controller.overloaded(inside))

    def _tick(self, state: BatchState) -> list[SkillEnd]:
        """The controller's tick in the alive worlds. If it raises, the controller's per-world state, the controls
        and the welds are put back as they were and each world is ticked alone: a world whose tick raises again
        fails with the reason, the others go on exactly as in the batched tick."""
        worlds = np.flatnonzero(self.alive())
        before = _TickUndo(self.controller, self.sim, state)
        try:
            return self.controller.tick(state, worlds)
        except Exception:  # find the world(s) it came from
            before.restore()
        ends = []
        for i in map(int, worlds):
            try:
                ends += self.controller.tick(state, np.array([i]))
            except Exception as e:  # a controller error in world i ends world i only
                self._internal_error(i, state, e)
        return ends

    # -- programs ------------------------------------------------------------------------------

    def _collect(self, state: BatchState, to_wait: list[int]) -> None:
        """Wait on each resumed world; answer queries (resuming all first), start motion skills."""
        while to_wait:
            again = []
            starts: dict[int, SkillRequest] = {}
            messages = wait_all([self.worlds[i].session for i in to_wait])
            for i, message in zip(to_wait, messages, strict=True):
                if isinstance(message, ProgramEnded):
                    self._end(i, state, message.error, message.output, settle=True)
                elif self._request(i, state, message):
                    again.append(i)
                elif not self.worlds[i].ended:
                    starts[i] = message
            for i, request in starts.items():
                try:
                    ends = self.controller.start(state, np.array([i]), request.name, self.worlds[i].pending_args)
                except Exception as e:  # a controller bug ends this world only
                    self._internal_error(i, state, e)
                    continue
                again += self._finish_skills(state, ends)
            to_wait = again

    def _request(self, i: int, state: BatchState, request: SkillRequest) -> bool:
        """Handle a skill call; True when the program was resumed at once (query or error)."""
        world = self.worlds[i]
        t = float(state.time[i] - self.t0[i])
        if len(world.calls) >= self.max_skill_calls:
            self._end(i, state, f"more than {self.max_skill_calls} skill calls")
            return False
        try:
            args = self.robot.check_call(request.name, request.args, self.box)
        except SkillArgumentError as e:
            world.calls.append(
                SkillCall(
                    skill=request.name, args=_jsonable(request.args), outcome="error", reason=str(e), started=t, ended=t
                )
            )
            world.session.resume(SkillReply(error=str(e)))
            return True
        call = SkillCall(skill=request.name, args=_jsonable(args), outcome="done", started=t, ended=t)
        world.calls.append(call)
        if self.kinds[request.name] == "motion":
            world.pending, world.pending_args = call, args
            return False
        try:
            call.result = self.controller.query(state, i, request.name, args)
        except QueryError as e:
            call.outcome, call.reason = "error", str(e)
            world.session.resume(SkillReply(error=str(e)))
            return True
        except Exception as e:  # a controller bug ends this world only
            self._internal_error(i, state, e, request.name)
            return False
        world.session.resume(SkillReply(value=call.result))
        return True

    def _finish_skills(self, state: BatchState, ends: list[SkillEnd]) -> list[int]:
        """Record finished motion skills and resume their programs; returns the resumed worlds."""
        resumed = []
        for end in ends:
            world = self.worlds[end.world]
            if world.ended or world.pending is None:
                continue
            if end.outcome == "internal_error":  # the controller raised in this world while running the skill
                self._internal_error(end.world, state, end.error or RuntimeError(end.reason))
                continue
            call, world.pending = world.pending, None
            call.outcome, call.reason, call.measured, call.result = end.outcome, end.reason, end.measured, end.result
            call.ended = float(state.time[end.world] - self.t0[end.world])
            world.events += _events_of(end, len(world.calls) - 1, call.ended)
            world.session.resume(SkillReply(value=end.result))
            resumed.append(end.world)
        return resumed

    def _internal_error(self, i: int, state: BatchState, error: BaseException, skill: str | None = None) -> None:
        """An exception inside the controller (a bug in robotool) ends world ``i`` as an internal error: it is logged
        in one line and its traceback recorded, its program ends and its goal is read now; ``skill`` is the query it
        answered (a motion skill in progress is named by the world)."""
        world = self.worlds[i]
        call = world.calls[-1] if skill is not None else world.pending
        where = f"in {call.skill}" if call is not None else "after the program ended"
        found = InternalError.of(error, f"the {self.robot.name} controller, {where}, world {i}")
        logger.error("%s (a bug in robotool: its traceback is the rollout's internal_error)", one_line(str(found)))
        world.internal_error = world.internal_error or found
        reason = capped(" ".join(f"internal error: controller error {where}: {found.reason}".split()), 500)
        if world.ended:  # settling after its program: the goal is read now, with the error
            world.error = world.error or reason
            if not world.finished:
                self._read_goals([i], state)
        else:
            self._end(i, state, reason)
        if call is not None:  # after the end, which marks a pending call as the program's error
            call.outcome, call.reason = "internal_error", reason

    def _end(self, i: int, state: BatchState, error: str | None, output: str = "", settle: bool = False) -> None:
        """The program of world ``i`` ended; with ``settle`` its world runs on before the goal is read."""
        world = self.worlds[i]
        if world.ended:
            return
        world.ended, world.error, world.output = True, error, output
        world.sim_time = float(state.time[i] - self.t0[i])
        self._mark_held(state, np.arange(self.sim.nworld) == i)
        if world.pending is not None:
            world.pending.outcome, world.pending.reason = "error", error
            world.pending.ended = world.sim_time
            world.pending = None
        world.session.close()
        if settle and state.failed[i] is None:
            world.settle_until = float(state.time[i]) + SETTLE_AFTER
        else:
            self._read_goals([i], state)

    def _finish_settled(self, state: BatchState, previous: BatchState) -> None:
        """Read the goal of every ended world that has settled (``SETTLE_AFTER`` past its end and every object still
        since ``previous``, the state a control tick before, and not speeding up over its settling), or whose physics
        failed while settling; fail those still moving ``SETTLE_LONGEST`` past their end."""
        if not any(world.ended and not world.finished for world in self.worlds):
            return  # no world settles: nothing to read in the step loop
        objects = self.object_bodies
        travel = np.linalg.norm(state.xpos[:, objects] - previous.xpos[:, objects], axis=2)  # (nworld, nbody)
        speed = travel / np.maximum(state.time - previous.time, 1e-9)[:, None]
        half_step = self.scene.model.opt.timestep / 2
        settled = []
        for i, world in enumerate(self.worlds):
            if not world.ended or world.finished:
                continue
            since_end = float(state.time[i]) - (world.settle_until - SETTLE_AFTER)
            world.settling.append(state.xpos[i, objects])
            still = speed[i].max() < STILL_SPEED and not _speeding_up(world.settling)
            if state.failed[i] is not None or (since_end >= SETTLE_AFTER - half_step and still):
                settled.append(i)
            elif since_end >= SETTLE_LONGEST - half_step:
                body = int(objects[np.argmax(speed[i])])
                moving = self.scene.object_names[self.scene.body_object[body]]
                world.error = world.error or (
                    f"the world did not come to rest: {moving} still moved at {speed[i].max():.2f} m/s "
                    f"{SETTLE_LONGEST:.0f} s after the program ended (a goal is read only once everything lies still)"
                )
                settled.append(i)
        if settled:
            self._read_goals(settled, state)

    def _read_goals(self, worlds: list[int], state: BatchState) -> None:
        """Read the goal in ``worlds`` (their runs are over): its conditions, the robot's and the goal's events."""
        conditions: dict[str, np.ndarray | list[bool]] = {**self.goal.conditions(state)}
        conditions.update(self.controller.robot_conditions(state, worlds))
        for i in worlds:
            world = self.worlds[i]
            world.finished = True
            world.sim_time = float(state.time[i] - self.t0[i])  # the world's whole run, its settling included
            world.conditions = {k: bool(v[i]) for k, v in conditions.items()}
            happened = [*goal_events(self.goal, i), *self.controller.robot_events(i)]
            seen = [_during_calls(e, e.time - float(self.t0[i]), world.calls) for e in happened]
            world.events = sorted(world.events + seen, key=lambda e: e.time)
            if state.failed[i] is not None and world.error is None:
                world.error = f"simulation failed: {state.failed[i]}"

    # -- physics bookkeeping -------------------------------------------------------------------

    def _observe(self, state: BatchState) -> None:
        """After a control tick: magnets, goal memory, touched objects, failures and caps."""
        alive = self.alive()
        self.magnets.update(self.sim, state, alive)
        self.sheets.update(self.sim, state, alive)
        self.goal.update(state, alive, alive & ~self.controller.overloaded(state))
        objects = self.object_bodies
        robot_contact = state.touching[:, self.scene.robot_body][:, :, objects].any(axis=1)  # (nworld, object bodies)
        moved = np.linalg.norm(state.xpos[:, objects] - self.start_xpos[:, objects], axis=2) > MOVED
        touched = np.zeros_like(self.touched)
        np.logical_or.at(touched.T, self.scene.body_object[objects], (robot_contact | moved).T)
        self.touched |= touched & alive[:, None]
        self._mark_held(state, alive)
        failed = np.array([f is not None for f in state.failed])
        over_time = state.time - self.t0 > self.max_sim_time
        for i in map(int, np.flatnonzero(alive & self.running() & (failed | over_time))):
            if failed[i]:
                self._end(i, state, f"simulation failed: {state.failed[i]}")
            else:
                self._end(i, state, f"simulated time over the {self.max_sim_time} s cap")

    def _mark_held(self, state: BatchState, worlds: np.ndarray) -> None:
        """An object welded to the robot (held) counts as touched."""
        for eq, obj in self.robot_welds:
            self.touched[:, obj] |= state.eq_active[:, eq] & worlds

    def _rollout(self, i: int, world: _World, seed: int) -> Rollout:
        names = self.scene.object_names
        success = bool(world.conditions) and all(world.conditions.values()) and world.error is None
        return Rollout(
            world=i,
            seed=seed,
            success=success,
            conditions=world.conditions,
            calls=world.calls,
            events=world.events,
            touched=[names[k] for k in np.flatnonzero(self.touched[i])],
            sim_time=world.sim_time,
            error=world.error,
            internal_error=world.internal_error,
            output=world.output,
        )


def _robot_welds(scene: Scene) -> list[tuple[int, int]]:
    """(equality id, object index) of every weld between a robot body and an object."""
    model = scene.model
    welds = []
    for eq in range(model.neq):
        if model.eq_type[eq] != mujoco.mjtEq.mjEQ_WELD or model.eq_objtype[eq] != mujoco.mjtObj.mjOBJ_BODY:
            continue
        a, b = model.eq_obj1id[eq], model.eq_obj2id[eq]
        for robot, other in ((a, b), (b, a)):
            if scene.robot_body[robot] and scene.body_object[other] >= 0:
                welds.append((eq, int(scene.body_object[other])))
    return welds


def scene_box(task: Task) -> SceneBox:
    """The box around the task's objects, the robot's start and what it can reach, for argument checks."""
    corners = [corner for obj in task.objects for part in geometry.object_parts(obj) for corner in part.aabb()]
    corners += [np.array(point) for point in robots.get(task.robot.type).rules.reach(task.limits)]
    if task.robot.position is not None:
        corners.append(np.array([*task.robot.position, 0.0]))
    points = np.array(corners, dtype=float).reshape(-1, 3)
    lo, hi = points.min(axis=0), points.max(axis=0)
    return SceneBox(lo=(float(lo[0]), float(lo[1]), float(lo[2])), hi=(float(hi[0]), float(hi[1]), float(hi[2])))


class _TickUndo:
    """What a control tick may change, saved before it: the controller's per-world state (its snapshot), the
    controls, the mocap positions and the welds."""

    def __init__(self, controller: SkillController, sim: BatchedSim, state: BatchState):
        self.controller, self.sim = controller, sim
        self.snapshot = controller.snapshot()
        self.ctrl, self.mocap_pos = sim.ctrl.copy(), sim.mocap_pos.copy()
        self.eq_active = state.eq_active.copy()

    def restore(self) -> None:
        """Put everything back as it was before the tick."""
        self.controller.restore(self.snapshot)
        self.sim.ctrl[...] = self.ctrl
        self.sim.mocap_pos[...] = self.mocap_pos
        changed = self.sim.state().eq_active != self.eq_active
        for w, eq in zip(*np.nonzero(changed), strict=True):
            self.sim.set_weld(np.array([w]), int(eq), bool(self.eq_active[w, eq]))


def _during_calls(event: Event, time: float, calls: list[SkillCall]) -> Event:
    """``event`` at ``time`` (seconds since the world's start), stamped with the call that was running then."""
    running = [k for k, c in enumerate(calls) if c.started <= time <= c.ended]
    return event.model_copy(update={"time": time, "call": running[-1] if running else None})


def _events_of(end: SkillEnd, call: int, time: float) -> list[Event]:
    """A finished skill's events stamped with its call and time; a stall, timeout or refusal is one too."""
    events = [e.model_copy(update={"call": call, "time": time}) for e in end.events]
    if end.outcome != "done" and not any(e.kind == end.outcome for e in events):
        events.append(Event(kind=end.outcome, call=call, time=time, measured=end.measured, detail=end.reason))
    return events


def _jsonable(args: tuple[Any, ...]) -> list[Any]:
    return [list(a) if isinstance(a, tuple) else a for a in args]
