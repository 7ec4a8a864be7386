"""The arm's payload: what it bears and what it pushes, however it does, judged against ``max_payload`` (a Kinova
Gen3 carries about 4 kg at mid range, 2 kg at full reach, and exerts about that weight, 39 N, at its end effector in
any direction; its servos and its grip alone would lift about 10 kg and press 100 N).

At each control tick, in a world whose gripper holds an object (its grasp weld is on) or whose robot bodies touch a
movable object, the load is read from the simulation. The held object, what is stuck to it (welded to it by magnets,
in a chain) and the movable objects that touch these, directly or through one another (what rides on it, what rides
on that) form one group; each other movable object a robot body touches forms one with what touches it. A group the
robot grasps, or whose net upward push from the robot's contacts is ``contact_lift`` at least, is held up: a plate
lifted on the open gripper's palm and fingers is carried as a grasped one is. When nothing in such a group touches
anything that does not move (the table, a fixed object) and no magnet anchors it to one, the arm carries the whole
group: its mass is its payload. Where the group touches a support, the arm carries only what it bears of it: the
upward force the grasp weld and the robot's contacts put on the group (the solver's contact forces,
:meth:`~robotool.sim.backend.BatchedSim.contact_forces`, on both backends) over g, never more than the group's mass.

The rest of the force the robot puts on a group (pushed or dragged along the table, pressed down, pulled through the
grasp, in any direction) is a push, which takes the rating as the weight it would hold up (its size over g): the arm's
load is the payload and the push, so it carries 4 kg, or pushes 39 N, or carries 2 kg while it pushes 20 N. A push is
not capped at the group's weight: a lever multiplies it (pressing a beam 5 cm before its fulcrum raises an anvil 10 cm
beyond it with twice the anvil's weight). A push is no load until it moves what it pushes: a tick of a push over the
limit counts once the pushes over it have moved what they push ``press_travel`` up or sideways (any point of it: a
beam turned about its middle moves its ends, not its centre), and worked the gripper along them as much as a push at
the limit does over ``press_travel`` (a steep lever raises its load centimetres while its end sinks millimetres), in
all over the run, each push as far as it moved them from where it went over (so a load pushed along in short strokes
counts as one long push). A press into a support is no load: it moves nothing but down (a block set down with its
target below its support, the stack under it sinking into its soft contacts), or it carries the gripper nowhere (the
fingers driven into the table, a beam pressed down onto the table sliding along under them). A lever's end pressed down
under a heavy anvil carries the gripper down and the anvil up centimetres, and holding it down after that counts too.

The moving parts of fixed objects (a button's face) are pushed too: the force the robot's bodies and what its grasp
carries (a held tool) put on such a part counts, up to what holds it where it is (its spring at its travel, its
guide's friction and its weight: more goes into its end stop), whether it moves or not (a stiff button held pressed).
The contact forces are read only in a scene whose movable objects together could weigh more than the limit or one of
whose moving parts could take more than it (a stiff button).

A real arm rides out a peak above its rated payload for an instant (the jerk as a load comes off its support, a
pushed crate hopping against a held tool for a tick), so a world fails only once its arm has carried (or pushed) more
than ``max_payload`` for ``payload_time`` (three control ticks) in all over the run; the time adds up across grasps, so
an overweight load cannot be carried in short hops with the grip opened between them. The world then fails
(the robot condition ``robot_carried_within_payload``), the move in progress is refused with a reason naming the
objects and the numbers, and the gripper lets go (the arm cannot hold it up); a tick over the limit is also one
whose state the goal may not count (:meth:`~.arm_controller.ArmController.overloaded`).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.robots.arm.arm_config import ArmConfig
from robotool.robots.arm.arm_grasp import GRAVITY, ArmParts, Grasp
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.sim.backend import BatchedSim, BatchState

PAYLOAD_CONDITION = "robot_carried_within_payload"  # the goal condition carrying more than max_payload breaks


@dataclass(frozen=True)
class Load:
    """What the arm carries in one world at one tick: the payload (kg), the mass of the groups it bears (kg), whether
    one of them rests on something that does not move, the object held (-1: none), the one the reason names (the
    held one, else the one the robot holds up or pushes hardest), the other members, and the force (N) it pushes,
    drags or presses with (``down``: mostly down) on the groups it does not hold up and the moving parts of fixed
    objects (``pushed``: the groups' members and the parts' objects; ``toward``: which way), ``spring`` N of it on the
    parts."""

    payload: float
    group_mass: float
    supported: bool
    held: int
    named: int
    stuck: tuple[int, ...]
    touching: tuple[int, ...]
    push: float
    down: bool
    pushed: np.ndarray  # (nobject,) bool: the members of the groups it pushes, the objects whose parts it pushes
    spring: float
    toward: np.ndarray  # (3,) which way it pushes (a unit vector)

    @property
    def by_contact(self) -> bool:
        """Some of it is borne by the robot's bodies' contacts rather than by a grasp."""
        return self.held < 0

    @property
    def total(self) -> float:
        """kg of the arm's rating it takes: the payload and the push (as the weight it would hold up)."""
        return self.payload + self.push / GRAVITY

    @property
    def held_still(self) -> float:
        """kg of the rating it takes whether or not what it pushes moves: the payload and the push on moving parts."""
        return self.payload + self.spring / GRAVITY

    @property
    def pushing(self) -> bool:
        """The push takes more of the rating than what is held up: the reason names the push."""
        return self.push / GRAVITY > self.payload


@dataclass(frozen=True)
class Groups:
    """The groups the robot may bear in one world (each a (nobject,) bool), whether each rests on a support, and
    their masses (kg): the held object's group first, where it holds one."""

    members: list[np.ndarray]
    supported: list[bool]
    mass: list[float]
    carried: np.ndarray  # (nobject,) bool: what the grasp welds join to the gripper


@dataclass(frozen=True)
class Bodies:
    """Which object owns each body, which bodies are the world's own and which are fixed objects' moving parts (fixed
    facts of a scene)."""

    member: np.ndarray  # (nbody, nobject) 1.0 where the body is the object's
    ground: np.ndarray  # (nbody,) bool: the world's own bodies (the table top), not the robot's nor an object's
    robot: np.ndarray  # (nbody,) bool: the robot's own bodies
    loose: np.ndarray  # the movable objects' bodies
    parts: np.ndarray  # (npart,) the bodies of fixed objects that move on their own joints (a button's face)
    part_object: np.ndarray  # (npart,) the object each part belongs to


@dataclass(frozen=True)
class Springs:
    """What holds each moving part of a fixed object where it is (a fixed fact of a scene): ``rest + stiffness *
    travel`` N, its travel read at ``qpos`` (a part on any other joint than one limited slide: no bound)."""

    qpos: np.ndarray  # (npart,) int: its joint's qpos address
    low: np.ndarray  # (npart,) m: its travel's start
    span: np.ndarray  # (npart,) m: its travel's length
    stiffness: np.ndarray  # (npart,) N/m
    rest: np.ndarray  # (npart,) N: its guide's friction and its weight (inf: no bound)

    def hold(self, qpos: np.ndarray) -> np.ndarray:
        """(npart,) N that hold each part where it is, at the joint positions ``qpos`` (nq,)."""
        return self.rest + self.stiffness * np.maximum(qpos[self.qpos] - self.low, 0.0)

    @classmethod
    def of(cls, model: mujoco.MjModel, bodies: np.ndarray) -> Springs:
        out = cls(np.zeros(len(bodies), dtype=int), *(np.zeros(len(bodies)) for _ in range(4)))
        for k, b in enumerate(bodies.tolist()):
            j = int(model.body_jntadr[b])
            out.qpos[k], out.low[k], out.span[k] = (
                model.jnt_qposadr[j],
                model.jnt_range[j][0],
                np.ptp(model.jnt_range[j]),
            )
            out.stiffness[k] = model.jnt_stiffness[j]
            slide = model.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE and model.jnt_limited[j]
            rest = model.body_mass[b] * GRAVITY + model.dof_frictionloss[model.jnt_dofadr[j]]
            out.rest[k] = rest if slide and model.body_jntnum[b] == 1 else np.inf
        return out

    @property
    def most(self) -> np.ndarray:
        """(npart,) N the most each part could take: held at the end of its travel."""
        return self.rest + self.stiffness * self.span


@dataclass
class PayloadState:
    """Per world (index first): how long the arm has carried more than its payload, whether it does now, and how far
    its pushes over the limit have moved what they push."""

    over_for: np.ndarray  # (nworld,) s over max_payload, added up over the run
    over_now: np.ndarray  # (nworld,) bool: over it at the last tick
    press_from: np.ndarray  # (nworld, nobject + 1, 3) m: the objects, the gripper as the push went over (NaN: not)
    press_frames: np.ndarray  # (nworld, nobject, 4) the objects' orientations then (unit quaternions; NaN: not)
    press_peak: np.ndarray  # (nworld,) m: the farthest the push now over the limit has moved them (see Payload._moves)
    pressed: np.ndarray  # (nworld,) m: how far the earlier pushes over the limit moved them, added up
    broke: list[str | None]  # the reason the arm carried too much (the world fails), once it did

    @classmethod
    def empty(cls, nworld: int, nobject: int) -> PayloadState:
        return cls(
            over_for=np.zeros(nworld),
            over_now=np.zeros(nworld, dtype=bool),
            press_from=np.full((nworld, nobject + 1, 3), np.nan),
            press_frames=np.full((nworld, nobject, 4), np.nan),
            press_peak=np.zeros(nworld),
            pressed=np.zeros(nworld),
            broke=[None] * nworld,
        )


class Payload:
    """Weighs what the arm carries in every world (state: :class:`PayloadState`)."""

    def __init__(self, sim: BatchedSim, parts: ArmParts, grasp: Grasp, limits: ArmLimits, config: ArmConfig):
        self.sim, self.parts, self.grasp, self.scene = sim, parts, grasp, sim.scene
        self.limit, self.time, self.lift = limits.max_payload, config.payload_time, config.contact_lift
        self.travel = config.press_travel
        owner = np.asarray(self.scene.body_object)
        robot = np.asarray(self.scene.robot_body, dtype=bool)  # (nbody,) the robot's own bodies
        member = (owner[:, None] == np.arange(len(self.scene.object_names))[None, :]).astype(float)
        loose = np.flatnonzero(member @ parts.movable > 0)
        model = self.scene.model
        fixed = (owner >= 0) & ~parts.movable[np.maximum(owner, 0)]
        moving = np.flatnonzero(fixed & (np.asarray(model.body_jntnum) > 0))
        self.bodies = Bodies(member, (owner < 0) & ~robot, robot, loose, moving, owner[moving])
        self.springs = Springs.of(model, moving)
        self.state = PayloadState.empty(sim.nworld, len(self.scene.object_names))
        movable_mass = np.asarray(sim.body_mass) @ (member * parts.movable[None, :])  # (nworld, nobject)
        heavy = bool((movable_mass.sum(axis=1) > self.limit).any())  # all of it might be too much
        self.relevant = heavy or bool((self.springs.most > self.limit * GRAVITY).any())

    def conditions(self) -> dict[str, list[bool]]:
        """The payload condition per world, where the scene's movable objects together could be too much to carry."""
        return {PAYLOAD_CONDITION: [b is None for b in self.state.broke]} if self.relevant else {}

    def check(self, state: BatchState, mask: np.ndarray) -> list[tuple[int, Load, str, dict[str, float]]]:
        """Weigh the load in the worlds in ``mask``; (world, load, reason, measured) for each world whose arm has now
        carried more than ``max_payload`` for ``payload_time`` (once per world)."""
        s = self.state
        s.over_now[mask] = False
        if not self.relevant:
            return []
        held = dict(self.grasp.holding(state, mask))
        things = np.concatenate([self.bodies.loose, self.bodies.parts])  # what a push may move
        touches = state.touching[:, self.bodies.robot][:, :, things].any(axis=(1, 2))
        worlds = [w for w in np.flatnonzero(mask & touches).tolist() + list(held) if s.broke[w] is None]
        groups = {w: self._groups(state, w, held.get(w, -1)) for w in dict.fromkeys(worlds)}
        weighed = np.array(list(groups), dtype=int)
        on_bodies = self.sim.contact_forces(weighed, self.bodies.robot)
        forces = np.einsum("kbi,bo->koi", on_bodies, self.bodies.member)  # (k, nobject, 3) on each object
        out, pressing = [], np.zeros(self.sim.nworld, dtype=bool)
        for k, w in enumerate(weighed.tolist()):
            tool = self._through_grasp(state, w, groups[w].carried)
            load = self._load(state, w, held.get(w, -1), groups[w], forces[k], on_bodies[k, self.bodies.parts], tool)
            if load is None or load.total <= self.limit + 1e-9:
                continue
            pressing[w] = load.push > load.spring
            if load.held_still <= self.limit + 1e-9 and not self._moves(state, w, load):
                continue
            s.over_now[w] = True
            s.over_for[w] += self.scene.control_dt
            if s.over_for[w] < self.time - 1e-9:
                continue
            reason, measured = self._words(load, float(s.over_for[w]))
            s.broke[w] = reason
            out.append((w, load, reason, measured))
        done = mask & ~pressing
        s.pressed[done] += s.press_peak[done]
        s.press_peak[done] = 0.0
        s.press_from[done] = np.nan
        s.press_frames[done] = np.nan
        return out

    def _through_grasp(self, state: BatchState, w: int, carried: np.ndarray) -> np.ndarray:
        """(npart, 3) N what the grasp carries in world ``w`` (``carried``: (nobject,) bool) puts on the moving
        parts of fixed objects it touches (a held tool pressing a button)."""
        bodies = np.asarray(self.bodies.member[:, carried].any(axis=1))
        if not state.touching[w][bodies][:, self.bodies.parts].any():
            return np.zeros((len(self.bodies.parts), 3))
        return self.sim.contact_forces(np.array([w]), bodies)[0, self.bodies.parts]

    def _moves(self, state: BatchState, w: int, load: Load) -> bool:
        """Whether a push over the limit counts at this tick: once the pushes over the limit have moved what they push
        ``press_travel`` up or sideways (or down, while it presses a moving part: a loose block pressed onto a stiff
        button's face, found by an adversarial run), any point of it (a beam turned about its middle moves its ends,
        not its centre), and worked the gripper as far along themselves as a push at the limit goes that far (a push
        of twice the limit counts after half the gripper's travel: a steep lever raises its load centimetres while its
        end sinks millimetres), in all, each from where it went over (a press into a support moves nothing but down,
        or carries the gripper nowhere: it is no load)."""
        s = self.state
        now = state.xpos[w, np.append(self.scene.object_body, self.parts.gripper)]
        frames = state.xquat[w, self.scene.object_body]
        if np.isnan(s.press_from[w]).any():
            s.press_from[w], s.press_frames[w] = now, frames
        moved = now - s.press_from[w]
        pushed = load.pushed & self.parts.movable
        objects = moved[:-1][pushed]
        turned = 2.0 * np.arccos(np.clip(np.abs(np.sum(frames * s.press_frames[w], axis=1)), 0.0, 1.0))
        on_parts = state.touching[w][np.asarray(self.bodies.member[:, pushed].any(axis=1))][:, self.bodies.parts].any()
        down = np.abs(objects[:, 2]) if on_parts else objects[:, 2]  # down onto a part that gives (a button's face)
        swept = np.maximum(np.linalg.norm(objects[:, :2], axis=1), down) + (self.parts.reach * turned)[pushed]
        lifted = float(np.max(swept, initial=0.0))
        along = float(moved[-1] @ load.toward) * load.total / self.limit  # the gripper's travel, as work at the limit
        s.press_peak[w] = max(float(s.press_peak[w]), min(lifted, along))
        return bool(s.pressed[w] + s.press_peak[w] >= self.travel)

    def _groups(self, state: BatchState, w: int, i: int) -> Groups:
        """The groups the robot may bear in world ``w`` (holding object ``i``, -1: none): the held object with what
        the grasp welds join to it, and each movable object a robot body touches, each grown through the movable
        objects that touch it (what rides on it, what rides on that)."""
        movable, member, ground = self.parts.movable, self.bodies.member, self.bodies.ground
        carried = self.grasp.carried(state, w) if i >= 0 else np.zeros(len(movable), dtype=bool)
        touch = state.touching[w].astype(float)
        objects = (member.T @ touch @ member) > 0  # (nobject, nobject) which objects touch
        on_ground = (touch[:, ground].sum(axis=1) @ member) > 0  # (nobject,) touching the table
        rests = on_ground | objects[:, ~movable].any(axis=1)
        touched = (touch[self.bodies.robot].sum(axis=0) @ member > 0) & movable & ~carried
        seeds = [carried & movable] if i >= 0 else []
        seeds += [np.arange(len(movable)) == o for o in np.flatnonzero(touched)]
        mass = np.asarray(self.sim.body_mass[w]) @ member
        out = Groups(members=[], supported=[], mass=[], carried=carried)
        taken = np.zeros(len(movable), dtype=bool)
        for group in seeds:
            if (group & taken).any():
                continue
            while True:
                grown = objects[group].any(axis=0) & movable & ~group
                if not grown.any():
                    break
                group = group | grown
            taken |= group
            out.members.append(group)
            out.supported.append(bool(rests[group].any() or (len(out.members) == 1 and (carried & ~movable).any())))
            out.mass.append(float(mass[group].sum()))
        return out

    def _load(
        self,
        state: BatchState,
        w: int,
        i: int,
        groups: Groups,
        force: np.ndarray,
        on_parts: np.ndarray,
        tool: np.ndarray,
    ) -> Load | None:
        """What the arm carries in world ``w`` holding object ``i`` (-1: none) of ``groups`` (see the module's doc),
        ``force`` (nobject, 3) N being what the robot's contacts put on each object, ``on_parts`` and ``tool``
        (npart, 3) N what they and what the grasp carries put on each moving part of a fixed object; None where it bears
        and pushes nothing."""
        force = np.where(self.parts.movable[:, None], force, 0.0)
        if i >= 0:  # the weld's force on it, but for what it passes on to moving parts (weighed there)
            force[i] -= self.sim.weld_load(np.array([w]), int(self.parts.grasp_eq[i]))[0, :3] + tool.sum(axis=0)
        up = force[:, 2]
        payload, mass, supported, borne = 0.0, 0.0, False, np.zeros(len(up), dtype=bool)
        push, pushed, pushed_on = 0.0, np.zeros(len(up), dtype=bool), np.zeros(3)
        for k, (group, rests, weight) in enumerate(zip(groups.members, groups.supported, groups.mass, strict=True)):
            on = force[group].sum(axis=0)
            lifted = (i >= 0 and k == 0) or float(on[2]) >= self.lift  # held, or held up by contact: borne
            if lifted and not rests:
                payload, mass, borne = payload + weight, mass + weight, borne | group
                continue
            share = min(weight, max(float(on[2]), 0.0) / GRAVITY) if lifted else 0.0
            rest = on - np.array([0.0, 0.0, share * GRAVITY])  # pushed, dragged or pressed with (the rest)
            pressed = float(np.linalg.norm(rest))
            if lifted:
                payload, mass, supported, borne = payload + share, mass + weight, True, borne | group
            if pressed > 0.0:
                push, pushed, pushed_on = push + pressed, pushed | group, pushed_on + rest
        on_parts = on_parts + tool
        held_by = np.minimum(np.linalg.norm(on_parts, axis=1), self.springs.hold(state.qpos[w]))
        spring = float(held_by.sum())
        push, pushed_on = push + spring, pushed_on + on_parts.sum(axis=0)
        np.add.at(force, self.bodies.part_object, on_parts)
        pushed[self.bodies.part_object[held_by > 0.0]] = True
        if not (borne.any() or push > 0.0):
            return None
        if i >= 0:
            named = i
        elif push / GRAVITY > payload:
            named = int(np.argmax(np.where(pushed, np.linalg.norm(force, axis=1), -np.inf)))
        else:
            named = int(np.argmax(np.where(borne, up, -np.inf)))
        stuck = tuple(int(o) for o in np.flatnonzero(groups.carried & self.parts.movable) if o != i)
        touching = tuple(int(o) for o in np.flatnonzero((borne | pushed) & ~groups.carried) if o != named)
        down = bool(-pushed_on[2] >= np.linalg.norm(pushed_on[:2]))
        toward = pushed_on / max(float(np.linalg.norm(pushed_on)), 1e-9)
        return Load(payload, mass, supported, i, named, stuck, touching, push, down, pushed, spring, toward)

    def _words(self, load: Load, over: float) -> tuple[str, dict[str, float]]:
        """The reason a load broke the payload limit, and its measures."""
        names = self.scene.object_names
        how = "touching" if load.supported or load.pushing else "riding on"
        along = [
            f"{', '.join(names[o] for o in objs)} {verb} it"
            for objs, verb in ((load.touching, how), (load.stuck, "stuck to"))
            if objs
        ]
        with_ = f" with {' and '.join(along)}" if along else ""
        on = " on the gripper" if load.by_contact else ""
        if load.pushing:
            verb = "press" if load.down else "push"
            besides = f" besides the {load.payload:.1f} kg it carries" if load.payload > 0 else ""
            name, force = names[load.named], f"{load.push:.0f} N"
            what = f"with {name}: {force}" if load.held >= 0 else f"{name}: {force} on it"
            reason = (
                f"cannot {verb} {what}{with_}{besides}, over the "
                f"{self.limit * GRAVITY:.0f} N the arm's {self.limit:.1f} kg payload allows ({verb}ed for {over:.1f} s)"
            )
        else:
            if load.supported:
                bears = "the gripper bears" if load.by_contact else "the arm bears"
                what = f"{bears} {load.payload:.1f} kg of its {load.group_mass:.1f} kg{with_} (a support the rest)"
            else:
                what = f"{load.payload:.1f} kg{' borne' if on else ''}{on}{with_}"
            if round(load.push):
                what += f" and pushes with {load.push:.0f} N"
            reason = (
                f"cannot lift {names[load.named]}: {what}, over the arm's {self.limit:.1f} kg payload "
                f"(carried for {over:.1f} s)"
            )
        measured = {
            "mass": round(load.payload, 3),
            "limit": self.limit,
            "group_mass": round(load.group_mass, 3),
            "force": round(load.push, 1),
            "riders": float(len(load.touching)),
            "stuck": float(len(load.stuck)),
            "contact": float(load.by_contact),
            "for": round(over, 3),
        }
        return reason, measured
