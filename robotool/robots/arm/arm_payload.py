"""The arm's payload: what it carries while it holds something, judged against ``max_payload`` (a Kinova Gen3
carries about 4 kg at mid range, 2 kg at full reach; its servos and its grip alone would lift about 10 kg).

At each control tick, in a world whose gripper holds an object (its grasp weld is on), the load is read from the
simulation: the held object, what is stuck to it (welded to it by magnets, in a chain) and the movable objects that
touch these, directly or through one another (what rides on it, what rides on that) form one group. When nothing
in the group touches anything that does not move (the table, a fixed object) and no magnet anchors it to one, the
arm carries the whole group: its mass is the payload. Where the group touches a support, the arm carries only what
the grasp weld bears of it, the upward pull the held object puts on the gripper over g, never more than the group's
mass: an object dragged or pushed along the table, or a tool pressed up into a button (its spring is no payload),
loads the arm with little or nothing; a block lifted while it scrapes along a wall, or a board tilted up by one
end, with what the grip actually holds up.

A real arm rides out a peak above its rated payload for an instant (the jerk as a load comes off its support, a
pushed crate hopping against a held tool for a tick), so a world fails only once its arm has carried more than
``max_payload`` for ``payload_time`` (three control ticks) in all over the run; the time adds up across grasps, so
an overweight load cannot be carried in short hops with the grip opened between them. The world then fails
(the robot condition ``robot_carried_within_payload``), the move in progress is refused with a reason naming the
objects and the numbers, and the gripper lets go (the arm cannot hold it up); a tick over the limit is also one
whose state the goal may not count (:meth:`~.arm_controller.ArmController.overloaded`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.arm.arm_config import ArmConfig
from robotool.robots.arm.arm_grasp import GRAVITY, ArmParts, Grasp
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.sim.backend import BatchedSim, BatchState

PAYLOAD_CONDITION = "robot_carried_within_payload"  # the goal condition carrying more than max_payload breaks


@dataclass(frozen=True)
class Load:
    """What the arm carries in one world at one tick: the payload (kg), the mass of the group that holds together
    with the held object (kg), whether that group rests on something that does not move, and its members."""

    payload: float
    group_mass: float
    supported: bool
    held: int
    stuck: tuple[int, ...]
    touching: tuple[int, ...]


@dataclass(frozen=True)
class Bodies:
    """Which object owns each body and which bodies are the world's own (fixed facts of a scene)."""

    member: np.ndarray  # (nbody, nobject) 1.0 where the body is the object's
    ground: np.ndarray  # (nbody,) bool: the world's own bodies (the table top), not the robot's nor an object's


@dataclass
class PayloadState:
    """Per world (index first): how long the arm has carried more than its payload, and whether it does now."""

    over_for: np.ndarray  # (nworld,) s over max_payload, added up over the run
    over_now: np.ndarray  # (nworld,) bool: over it at the last tick
    broke: list[str | None]  # the reason the arm carried too much (the world fails), once it did

    @classmethod
    def empty(cls, nworld: int) -> PayloadState:
        return cls(over_for=np.zeros(nworld), over_now=np.zeros(nworld, dtype=bool), broke=[None] * nworld)


class Payload:
    """Weighs what the arm carries in every world (state: :class:`PayloadState`)."""

    def __init__(self, sim: BatchedSim, parts: ArmParts, grasp: Grasp, limits: ArmLimits, config: ArmConfig):
        self.sim, self.parts, self.grasp, self.scene = sim, parts, grasp, sim.scene
        self.limit, self.time = limits.max_payload, config.payload_time
        owner = np.asarray(self.scene.body_object)
        robot = np.zeros(len(owner), dtype=bool)
        robot[np.asarray(self.scene.robot_body, dtype=int)] = True
        member = (owner[:, None] == np.arange(len(self.scene.object_names))[None, :]).astype(float)
        self.bodies = Bodies(member=member, ground=(owner < 0) & ~robot)
        self.state = PayloadState.empty(sim.nworld)
        movable_mass = np.asarray(sim.body_mass) @ (member * parts.movable[None, :])  # (nworld, nobject)
        self.relevant = bool((movable_mass.sum(axis=1) > self.limit).any())  # all of it might be too much

    def conditions(self) -> dict[str, list[bool]]:
        """The payload condition per world, where the scene's movable objects together could be too much to carry."""
        return {PAYLOAD_CONDITION: [b is None for b in self.state.broke]} if self.relevant else {}

    def check(self, state: BatchState, mask: np.ndarray) -> list[tuple[int, int, str, dict[str, float]]]:
        """Weigh the load in the worlds in ``mask``; (world, held object, reason, measured) for each world whose arm
        has now carried more than ``max_payload`` for ``payload_time`` (once per world)."""
        s = self.state
        s.over_now[mask] = False
        if not self.relevant:
            return []
        out = []
        for w, i in self.grasp.holding(state, mask):
            if s.broke[w] is not None:
                continue
            load = self.load(state, w, i)
            if load.payload <= self.limit + 1e-9:
                continue
            s.over_now[w] = True
            s.over_for[w] += self.scene.control_dt
            if s.over_for[w] < self.time - 1e-9:
                continue
            reason, measured = self._words(load, float(s.over_for[w]))
            s.broke[w] = reason
            out.append((w, i, reason, measured))
        return out

    def load(self, state: BatchState, w: int, i: int) -> Load:
        """What the arm carries in world ``w`` holding object ``i`` (see the module's doc)."""
        movable, member, ground = self.parts.movable, self.bodies.member, self.bodies.ground
        carried = self.grasp.carried(state, w)
        touch = state.touching[w].astype(float)
        objects = (member.T @ touch @ member) > 0  # (nobject, nobject) which objects touch
        on_ground = (touch[:, ground].sum(axis=1) @ member) > 0  # (nobject,) touching the table
        rests = on_ground | objects[:, ~movable].any(axis=1)
        group = carried & movable
        while True:
            grown = objects[group].any(axis=0) & movable & ~group
            if not grown.any():
                break
            group |= grown
        mass = float((np.asarray(self.sim.body_mass[w]) @ member)[group].sum())
        supported = bool((carried & ~movable).any() or rests[group].any())
        payload = mass
        if supported and mass > self.limit:
            force = self.sim.weld_load(np.array([w]), int(self.parts.grasp_eq[i]))[0, :3]
            payload = min(mass, max(-float(force[2]), 0.0) / GRAVITY)
        stuck = tuple(int(o) for o in np.flatnonzero(carried & movable) if o != i)
        touching = tuple(int(o) for o in np.flatnonzero(group & ~carried))
        return Load(payload, mass, supported, i, stuck, touching)

    def _words(self, load: Load, over: float) -> tuple[str, dict[str, float]]:
        """The reason a load broke the payload limit, and its measures."""
        names = self.scene.object_names
        how = "touching" if load.supported else "riding on"
        along = [
            f"{', '.join(names[o] for o in objs)} {verb} it"
            for objs, verb in ((load.touching, how), (load.stuck, "stuck to"))
            if objs
        ]
        with_ = f" with {' and '.join(along)}" if along else ""
        if load.supported:
            what = f"the arm bears {load.payload:.1f} kg of its {load.group_mass:.1f} kg{with_} (a support the rest)"
        else:
            what = f"{load.payload:.1f} kg{with_}"
        reason = (
            f"cannot lift {names[load.held]}: {what}, over the arm's {self.limit:.1f} kg payload "
            f"(carried for {over:.1f} s)"
        )
        measured = {
            "mass": round(load.payload, 3),
            "limit": self.limit,
            "group_mass": round(load.group_mass, 3),
            "riders": float(len(load.touching)),
            "stuck": float(len(load.stuck)),
            "for": round(over, 3),
        }
        return reason, measured
