"""The quadruped's move runner: it runs a skill's plan, one straight move at a time, in every world at once.

A plan (:data:`SkillPlan`, made by :mod:`.plans`) yields :class:`Move` s and is sent each move's outcome; the runner
starts a move, steers the x-y setpoint toward where the terrain lets it stop (:mod:`.terrain_following`), and
ends it once the body is there and still (done, or refused with the terrain's finding), when it makes no progress
(stalled), or when the referee stops it (:meth:`MoveRunner.refuse`, :meth:`MoveRunner.fell`).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import OFF
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import feet
from robotool.robots.quadruped.terrain import RISE, Finding, clamp
from robotool.robots.quadruped.terrain_following import TerrainFollowing
from robotool.sim.embodiment import SkillEnd, error_end
from robotool.vocabulary import MoveEnd

"""How a move or a skill ended: outcome (``done``, ``stalled``, ``refused``...), reason, measured values."""


@dataclass
class Move:
    """One straight move to ``goal`` (x-y); ``pushing`` is the object index being pushed or -1, and ``face`` (rad,
    counter-clockwise) how far a push turns the body off the quarter heading it holds. A move with a ``turn`` (rad,
    the heading to reach) turns in place at ``goal`` instead."""

    goal: np.ndarray
    pushing: int = -1
    face: float = 0.0
    turn: float = float("nan")


SkillPlan = Generator[Move, MoveEnd, MoveEnd | None]
"""A motion skill's plan: yields moves, is sent each one's outcome, returns the skill's (None: done)."""


@dataclass
class MoveState:
    """Per world (index first): the plan and the move running there."""

    plans: list[SkillPlan | None]  # the plan of the skill in progress
    moving: np.ndarray  # (nworld,) bool: a move is running
    origin: np.ndarray  # (nworld, 2) body position where the move started
    u: np.ndarray  # (nworld, 2) its direction
    length: np.ndarray  # (nworld,) its length
    pushing: np.ndarray  # (nworld,) the object it pushes (-1: none)
    best: np.ndarray  # (nworld,) m: the least distance to its end so far
    progress_time: np.ndarray  # (nworld,) s: when it last came 1 cm closer
    setpoint: np.ndarray  # (nworld, 2) the x-y setpoint
    turn: np.ndarray  # (nworld,) rad: the heading a turn in place reaches (NaN: a straight move)

    @classmethod
    def empty(cls, nworld: int, setpoint: np.ndarray) -> MoveState:
        return cls(
            plans=[None] * nworld,
            moving=np.zeros(nworld, dtype=bool),
            origin=np.zeros((nworld, 2)),
            u=np.tile([1.0, 0.0], (nworld, 1)),
            length=np.zeros(nworld),
            pushing=np.full(nworld, -1),
            best=np.full(nworld, np.inf),
            progress_time=np.zeros(nworld),
            setpoint=setpoint,
            turn=np.full(nworld, np.nan),
        )


class MoveRunner:
    """Runs plans of straight moves (state: :class:`MoveState`); ``on_push(w, index)`` is told when a push of
    object ``index`` starts in world ``w``."""

    def __init__(
        self,
        senses: Senses,
        terrain: TerrainFollowing,
        config: QuadrupedConfig,
        on_push: Callable[[int, int], None],
    ):
        self.senses, self.terrain, self.config, self.on_push = senses, terrain, config, on_push
        self.sim, self.ids = senses.sim, senses.facts.ids
        state = senses.state
        self.state = MoveState.empty(self.sim.nworld, state.qpos[:, self.ids.qpos[:2]].copy())
        self.sim.ctrl[:, self.ids.leg_actuator] = terrain.state.legs
        self.hold(np.arange(self.sim.nworld))

    def begin(self, w: int, plan: SkillPlan) -> SkillEnd | None:
        """Run ``plan`` in world ``w``: start its first move, or end the skill at once."""
        self.state.plans[w] = plan
        try:
            move = next(plan)
        except StopIteration as stop:
            return self._end(w, stop.value)
        self._start_move(w, move)
        return None

    def advance(self, w: int, outcome: MoveEnd) -> SkillEnd | None:
        """The current move ended with ``outcome``: start the plan's next move or end the skill (with outcome
        ``error`` when the plan raises: an advanced plan cannot be rolled back, so this world's error is its own)."""
        plan = self.state.plans[w]
        assert plan is not None
        try:
            move = plan.send(outcome)
            self._start_move(w, move)
        except StopIteration as stop:
            return self._end(w, stop.value)
        except Exception as e:  # any error in this world's plan ends this world's skill only
            self._end(w, None)
            return error_end(w, e)
        return None

    def refuse(self, w: int, reason: str, measured: dict[str, float], ends: list[SkillEnd]) -> bool:
        """Stop the move in progress in world ``w``, if any: its skill is refused with ``reason``. Returns whether a
        move was in progress."""
        if not (self.state.moving[w] and self.state.plans[w] is not None):
            return False
        end = self.advance(w, ("refused", reason, measured))
        if end is not None:
            ends.append(end)
        return True

    def fell(self, w: int, reason: str, measured: dict[str, float]) -> SkillEnd | None:
        """The robot fell in world ``w``: the skill in progress, if any, ends ``fell``; the robot holds still."""
        end = None
        if self.state.plans[w] is not None:
            self.state.plans[w] = None
            end = SkillEnd(world=int(w), outcome="fell", reason=reason, measured=measured)
        self.state.moving[w] = False
        self.hold(np.array([w]))
        return end

    def _start_move(self, w: int, move: Move) -> None:
        s = self.state
        here = self.senses.position(w)
        delta = move.goal - here
        length = float(np.linalg.norm(delta))
        s.moving[w] = True
        s.origin[w] = here
        s.u[w] = delta / length if length > 1e-9 else np.array([1.0, 0.0])
        s.length[w] = length
        s.pushing[w] = move.pushing
        s.turn[w] = move.turn
        self.terrain.start_move(w)
        if move.pushing >= 0:
            self.on_push(w, move.pushing)
            self.sim.ctrl[w, self.ids.yaw_actuator] = self._quarter_heading(w) + move.face
        s.best[w], s.progress_time[w] = np.inf, float(self.senses.state.time[w])

    def _quarter_heading(self, worlds: np.ndarray | int) -> np.ndarray:
        """The heading a robot holds in ``worlds``: the nearest quarter turn to its heading now (rad)."""
        quarter = np.pi / 2
        return np.round(self.senses.yaw(worlds) / quarter) * quarter

    def _end(self, w: int, outcome: MoveEnd | None) -> SkillEnd:
        self.state.plans[w] = None
        self.state.moving[w] = False
        self.hold(np.array([w]))
        kind, reason, measured = outcome or ("done", None, {})
        return SkillEnd(world=int(w), outcome=kind, reason=reason, measured=measured)

    def hold(self, worlds: np.ndarray) -> None:
        """Stand still where the body is, lift motor off."""
        ctrl, act = self.sim.ctrl, self.ids.actuator
        self.state.setpoint[worlds] = self.senses.state.qpos[worlds][:, self.ids.qpos[:2]]
        ctrl[worlds[:, None], act[:2]] = self.state.setpoint[worlds]
        ctrl[worlds, act[2]] = OFF
        ctrl[worlds[:, None], act[3:]] = 0.0
        ctrl[worlds, self.ids.yaw_actuator] = self._quarter_heading(worlds)  # (a push's twist does not build up)
        self.terrain.state.lift[worlds] = np.nan

    def drive(self, worlds: np.ndarray, ends: list[SkillEnd]) -> None:
        """Turn the worlds that turn in place; elsewhere read the terrain where needed, then lift, stop, refuse or
        advance, in all moving worlds at once."""
        turning = ~np.isnan(self.state.turn[worlds])
        if turning.any():
            self._turn(worlds[turning], ends)
            worlds = worlds[~turning]
            if not worlds.size:
                return
        s, t, terrain, config = self.state, self.terrain.state, self.terrain, self.config
        state = self.senses.state
        q, qd = state.qpos[worlds][:, self.ids.qpos], state.qvel[worlds][:, self.ids.qvel]
        u, length, pushing = s.u[worlds], s.length[worlds], s.pushing[worlds]
        travel = np.einsum("ki,ki->k", q[:, :2] - s.origin[worlds], u)
        centres = feet(state, self.ids)[worlds]
        local, local_objects, under_torso = terrain.local(worlds, centres, q[:, :2], u, pushing)
        index = terrain.indices(worlds, travel)
        scan_t0 = t.scan_t0[worlds]
        stale = t.rescan[worlds] | np.any((index < 0) | (index >= terrain.samples), axis=1)
        stale |= (travel > scan_t0 + config.scan_ahead / 2) & (length > scan_t0 + config.scan_ahead)
        stored = terrain.gather(t.heights, worlds, index)
        pushed = (local_objects == pushing[:, None, None]) & (local_objects >= 0)
        stale |= np.any(~pushed & (np.abs(local - stored) > RISE), axis=(1, 2))
        if stale.any():
            terrain.scan(worlds[stale], travel[stale], centres[stale], u[stale], length[stale], pushing[stale])
            index = terrain.indices(worlds, travel)
            stored = terrain.gather(t.heights, worlds, index)
        local = np.where(pushed, stored, local)
        waiting = terrain.lift(worlds, q, qd, travel, centres, local, under_torso, index)
        stop = self._steer(worlds, q, waiting)
        self._check_arrival(worlds, q, qd, travel, stop, ends)

    def _steer(self, worlds: np.ndarray, q: np.ndarray, waiting: np.ndarray) -> np.ndarray:
        """Move the x-y setpoints toward the stopping points at walking speed, leashed to the bodies; return the
        stopping points (k, 2)."""
        s, config = self.state, self.config
        body = q[:, :2]
        sp = s.setpoint[worlds]
        stop = s.origin[worlds] + s.u[worlds] * self.terrain.state.stop[worlds][:, None]
        to_stop = stop - sp
        gap = lengths(to_stop)
        go = ~waiting & (gap > 1e-9) & (lengths(sp - body) < config.leash)
        step = np.minimum(gap, config.walk_speed * self.senses.scene.control_dt)
        direction = to_stop / np.maximum(gap, 1e-9)[:, None]
        sp = sp + np.where(go[:, None], direction * step[:, None], 0.0)
        velocity = np.where((go & (gap > step))[:, None], direction * config.walk_speed, 0.0)
        s.setpoint[worlds] = sp
        self.sim.ctrl[worlds[:, None], self.ids.actuator[:2]] = sp + self.senses.facts.lead * velocity
        return stop

    def _turn(self, worlds: np.ndarray, ends: list[SkillEnd]) -> None:
        """Move the heading setpoints of turns in place toward their headings at turning speed (x-y held, legs as
        they stand: :meth:`.plans.Plans.turn` turns only where the feet's arcs stay level and the body's sweep is
        clear); end the turns that are there and still, or that stalled."""
        s, config, ids = self.state, self.config, self.ids
        state, ctrl = self.senses.state, self.sim.ctrl
        setpoint = ctrl[worlds, ids.yaw_actuator]
        step = config.turn_speed * self.senses.scene.control_dt
        ctrl[worlds, ids.yaw_actuator] = setpoint + clamp(s.turn[worlds] - setpoint, -step, step)
        yaw = self.senses.yaw(worlds)
        reach = float(np.linalg.norm(self.senses.facts.half))  # m a corner travels per rad
        remaining = np.abs(s.turn[worlds] - yaw) * reach
        qvel = state.qvel[worlds]
        still = (np.abs(qvel[:, ids.qvel[:3]]).max(axis=1) < config.settled_speed) & (
            np.abs(qvel[:, [*ids.qvel[3:], ids.yaw_qvel]]).max(axis=1) < config.settled_turn
        )
        there = (np.abs(s.turn[worlds] - yaw) < config.turn_arrived) & still
        self._end_moves(worlds, state.qpos[worlds][:, ids.qpos], remaining, there, ends)

    def _check_arrival(
        self,
        worlds: np.ndarray,
        q: np.ndarray,
        qd: np.ndarray,
        travel: np.ndarray,
        stop: np.ndarray,
        ends: list[SkillEnd],
    ) -> None:
        """End the moves whose body (coordinates ``q`` (k, 5), moving at ``qd``) reached its stopping point ``stop``
        (k, 2) (done or refused), stalled or ran out of time."""
        s, t, config = self.state, self.terrain.state, self.config
        speed = np.abs(qd)
        still = (speed[:, :3].max(axis=1) < config.settled_speed) & (speed[:, 3:].max(axis=1) < config.settled_turn)
        there = (lengths(q[:, :2] - stop) < config.arrived) & still
        length = s.length[worlds]
        remaining = np.abs(length - travel)
        finished = there & ((t.stop[worlds] >= length - 1e-9) | np.array([t.findings[w] is not None for w in worlds]))
        self._end_moves(worlds, q, remaining, finished, ends)

    def _end_moves(
        self, worlds: np.ndarray, q: np.ndarray, remaining: np.ndarray, finished: np.ndarray, ends: list[SkillEnd]
    ) -> None:
        """Advance the plans of the moves that ``finished`` (done, or refused with the terrain's finding) or made no
        1 cm of progress (``remaining``, m) for the stall time."""
        s, t, config = self.state, self.terrain.state, self.config
        now = self.senses.state.time[worlds]
        better = remaining < s.best[worlds] - 0.01
        s.best[worlds] = np.where(better, remaining, s.best[worlds])
        s.progress_time[worlds] = np.where(better, now, s.progress_time[worlds])
        stalled = ~finished & (now - s.progress_time[worlds] > config.stall_time)
        for k in np.flatnonzero(finished | stalled):
            w = int(worlds[k])
            finding = t.findings[w]
            if stalled[k] and not np.isnan(s.turn[w]):
                short = float(np.degrees(abs(s.turn[w] - self.senses.yaw(w))))
                outcome: MoveEnd = (
                    "stalled",
                    f"the turn was blocked at [{q[k, 0]:.2f}, {q[k, 1]:.2f}], {short:.0f} deg short of the heading",
                    {"angle": round(short, 1)},
                )
            elif stalled[k]:
                outcome = (
                    "stalled",
                    f"blocked at [{q[k, 0]:.2f}, {q[k, 1]:.2f}], {remaining[k]:.2f} m short of the goal",
                    {"distance": round(float(remaining[k]), 3)},
                )
            elif finding is not None:
                outcome = ("refused", finding.describe(), finding_measured(finding))
            else:
                outcome = ("done", None, {})
            end = self.advance(w, outcome)
            if end is not None:
                ends.append(end)


def lengths(v: np.ndarray) -> np.ndarray:
    """The lengths (k,) of x-y vectors ``v`` (k, 2), as ``np.linalg.norm(v, axis=1)`` gives them."""
    x, y = v[:, 0], v[:, 1]
    return np.sqrt(x * x + y * y)


def finding_measured(finding: Finding) -> dict[str, float]:
    """A finding's measured values, as a refusal reports them (a want of grip: the surface's friction)."""
    return {
        "friction" if finding.kind == "grip" else finding.kind: finding.measured,
        "limit": finding.limit,
        "x": round(finding.where[0], 3),
        "y": round(finding.where[1], 3),
    }
