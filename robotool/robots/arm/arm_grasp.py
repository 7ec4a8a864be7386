"""The arm's grasp: what the closed fingers hold, and whether the grip can carry it.

``close_gripper`` holds an object only when both fingers touch it from its sides (not resting on top
of it, nor pressing their fronts on a face of it), it lies between them (beside the fingers none of it
reaches past their inner faces), and it is no wider across them than the opening (a sheet is pinched
when both fingertips press on it: they gather a fold of it); it is then attached
rigidly by the weld ``robot_grasp__<object>`` (one per movable object) at the current pose, as
grasp-assisted simulators do, and released by ``open_gripper``. Otherwise the call reports what the
fingers met and why nothing is held, as a typed ``grasp_failed`` event with the measured values.

The weld stands for a friction grip, so it holds only what that grip can (:class:`Hold`): the pads must
cover at least half (``edge_share``) of what they could of the object across their width (a pinch of its last
millimetres at an edge is no grip), and the squeeze of ``grip_force`` per pad, at the friction the pads meet on that
object (:func:`~robotool.sim.build.contact_friction`: a slippery one's own), must carry the load, the weight of
the held object and of everything joined to it, and its torque about the pads (the weight's lever along
the pads against the grip's depth across them, its lever along the closing axis against the width between
them). A grip that cannot is refused at ``close_gripper``; one that stops holding when more is joined to
it (a magnetic chain grown from it) lets go at once and the skill reports it (the tunables are in
:class:`~robotool.robots.arm.arm_config.ArmConfig`).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import mujoco
import numpy as np

from robotool.robots.arm.arm_body import AXES, GRIPPER_BODY, SIDES, grasp_eq_name, graspable_points, held_objects
from robotool.robots.arm.arm_config import ARM, ArmConfig
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.rollout import Event, GraspFailure
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.build import DEFAULT_FRICTION, contact_friction
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import SkillEnd

GRAVITY = 9.81  # m/s^2


@dataclass(frozen=True)
class Hold:
    """How the pads engage a held object: depth across the pads (world x) and the least that is a grip there,
    width between them (world y), and the engaged patch's centre relative to the gripper centre."""

    depth: float
    edge_need: float
    width: float
    centre: np.ndarray

    def need(self, weight: float, lever: np.ndarray, grip: float) -> tuple[float, float]:
        """The depth across the pads and the width between them that hold ``weight`` (N) whose centre lies
        ``lever`` (x, y) from the patch: the weight's torque over the grip's friction couple (``grip``: N of
        friction each pad holds)."""
        return max(self.edge_need, weight * abs(float(lever[0])) / grip), weight * abs(float(lever[1])) / grip


@dataclass(frozen=True)
class Grip:
    """Where the fingers are in one world: the inner faces across the closing axis (world y), their x and z spans."""

    left: float
    right: float
    x: tuple[float, float]
    z: tuple[float, float]

    @property
    def gap(self) -> float:
        return self.left - self.right


@dataclass(frozen=True)
class ArmParts:
    """The ids of the gripper's parts and, per object, its geoms, its grasp weld and what it is (no per-world state)."""

    gripper: int  # the gripper body
    xyz_act: np.ndarray  # (3,) the x, y, z servos
    finger_act: np.ndarray  # (2,) the fingers' servos (left, right)
    finger_body: np.ndarray  # (2,)
    finger_qpos: np.ndarray  # (2,)
    xyz_dof: np.ndarray  # (3,)
    grasp_eq: np.ndarray  # (nobject,) each object's grasp weld (-1: not graspable)
    object_geoms: tuple[np.ndarray, ...]  # each object's geoms
    movable: np.ndarray  # (nobject,) bool
    sheet: np.ndarray  # (nobject,) bool
    friction: np.ndarray  # (nobject,) each object's declared friction, which the pads meet
    reach: np.ndarray  # (nobject,) m from a rigid object's centre to its farthest corner (a cloth's links: 0)

    @classmethod
    def of(cls, scene: Scene) -> ArmParts:
        model, objects = scene.model, scene.task.objects
        graspable = [o.movable and o.shape != "cloth" for o in objects]
        return cls(
            gripper=model.body(GRIPPER_BODY).id,
            xyz_act=np.array([model.actuator(f"robot_{a}").id for a in AXES]),
            finger_act=np.array([model.actuator(f"robot_finger_{s}").id for s in SIDES]),
            finger_body=np.array([model.body(f"robot_finger_{s}").id for s in SIDES]),
            finger_qpos=np.array([model.jnt_qposadr[model.joint(f"robot_finger_{s}").id] for s in SIDES]),
            xyz_dof=np.array([model.jnt_dofadr[model.joint(f"robot_{a}").id] for a in AXES]),
            grasp_eq=np.array(
                [model.equality(grasp_eq_name(o.name)).id if g else -1 for o, g in zip(objects, graspable, strict=True)]
            ),
            object_geoms=tuple(
                np.flatnonzero(scene.body_object[model.geom_bodyid] == i) for i in range(len(scene.object_names))
            ),
            movable=np.array([o.movable for o in objects]),
            sheet=np.array([o.is_sheet for o in objects]),
            friction=np.array([o.friction or DEFAULT_FRICTION for o in objects]),
            reach=np.array([0.0 if o.shape == "cloth" else float(np.linalg.norm(o.size)) / 2 for o in objects]),
        )


@dataclass
class GraspState:
    """Per world (index first): the grip on the held object (valid while its grasp weld is on) and the grips that
    gave way since the last skill ended."""

    hold_depth: np.ndarray  # (nworld,) m: the held object's Hold
    hold_edge: np.ndarray  # (nworld,) m
    hold_width: np.ndarray  # (nworld,) m
    hold_centre: np.ndarray  # (nworld, 3) m
    overloaded_for: np.ndarray  # (nworld,) s the grip's twist or tilt has been past what it holds since the grasp
    let_go: list[list[Event]]  # grips that gave way, told at the next skill end

    @classmethod
    def empty(cls, nworld: int) -> GraspState:
        return cls(
            hold_depth=np.zeros(nworld),
            hold_edge=np.zeros(nworld),
            hold_width=np.zeros(nworld),
            hold_centre=np.zeros((nworld, 3)),
            overloaded_for=np.zeros(nworld),
            let_go=[[] for _ in range(nworld)],
        )


class Grasp:
    """Closes the fingers into a grasp, or says why nothing is held, and lets go of a grip that cannot carry its load
    (state: :class:`GraspState`)."""

    def __init__(self, sim: BatchedSim, parts: ArmParts, limits: ArmLimits, config: ArmConfig):
        self.sim, self.parts, self.limits, self.config, self.scene = sim, parts, limits, config, sim.scene
        self.state = GraspState.empty(sim.nworld)

    def carried(self, state: BatchState, w: int) -> np.ndarray:
        """Objects the gripper carries in world ``w``: held, or joined to what it carries by an active weld."""
        return self._joined(state, w, self.parts.gripper)

    def _joined(self, state: BatchState, w: int, start: int) -> np.ndarray:
        """Objects joined to body ``start`` in world ``w`` by a chain of active welds (its own object too); a chain
        does not pass through the world (a pinned sheet's weld holds it to the table, not to other pinned sheets)."""
        model, owner = self.scene.model, self.scene.body_object
        carried = np.zeros(len(self.scene.object_names), dtype=bool)
        reach = {start}
        grown = True
        while grown:
            grown = False
            for eq in np.flatnonzero(state.eq_active[w]):
                a, b = int(model.eq_obj1id[eq]), int(model.eq_obj2id[eq])
                for x, y in ((a, b), (b, a)):
                    if x in reach and y not in reach and y != 0:
                        reach.add(y)
                        grown = True
        for body in reach:
            if owner[body] >= 0:
                carried[owner[body]] = True
        return carried

    def _grip(self, state: BatchState, w: int) -> Grip:
        c = state.xpos[w, self.parts.gripper]
        q_left, q_right = state.qpos[w, self.parts.finger_qpos]
        return Grip(
            left=float(c[1] + q_left - self.config.finger_half[1]),
            right=float(c[1] - q_right + self.config.finger_half[1]),
            x=(float(c[0] - self.config.finger_half[0]), float(c[0] + self.config.finger_half[0])),
            z=(
                float(c[2] + self.config.finger_z - self.config.finger_half[2]),
                float(c[2] + self.config.finger_z + self.config.finger_half[2]),
            ),
        )

    def grasp(self, state: BatchState, w: int) -> SkillEnd:
        """Hold the object both fingers grip from its sides, if it fits the opening; else say why nothing is held."""
        names = self.scene.object_names
        held = held_objects(self.scene, state)[w]
        if held >= 0:
            return SkillEnd(w, "done", f"holding {names[held]}", events=(Event(kind="grasped", object=names[held]),))
        grip = self._grip(state, w)
        owner = self.scene.body_object
        touch = state.touching[w][self.parts.finger_body]  # (2, nbody)
        by_finger = [set(owner[np.flatnonzero(t)]) - {-1} for t in touch]
        for finger, under in zip(by_finger, self._resting_under(state, w, grip), strict=True):
            finger |= under
        both = sorted(i for i in by_finger[0] & by_finger[1] if self.parts.grasp_eq[i] >= 0)
        failures: list[tuple[GraspFailure, int, dict[str, float]]] = []
        for i in both:
            cause, measured = self._fit(state, w, i, grip)
            if cause is None:
                hold = self._engaged(state, w, i, grip)
                weak = self._weak(state, w, i, hold)
                if weak:
                    failures.append(("weak_grip", i, weak))
                    continue
                self.state.hold_depth[w], self.state.hold_edge[w], self.state.hold_width[w] = (
                    hold.depth,
                    hold.edge_need,
                    hold.width,
                )
                self.state.hold_centre[w] = hold.centre
                self.state.overloaded_for[w] = 0.0
                self.sim.set_weld(np.array([w]), int(self.parts.grasp_eq[i]), True)
                return SkillEnd(
                    w,
                    "done",
                    f"holding {names[i]}",
                    measured,
                    events=(Event(kind="grasped", object=names[i], measured=measured),),
                )
            failures.append((cause, i, measured))
        if not failures:
            one = sorted(i for i in by_finger[0] ^ by_finger[1] if self.parts.grasp_eq[i] >= 0)
            if one:
                failures.append(("one_finger", one[0], {}))
            else:
                failures.append(("nothing_between", *self._nearest(state, w)))
        cause, i, measured = failures[0]
        event = Event(
            kind="grasp_failed", object=names[i] if i >= 0 else None, limit="grasp", cause=cause, measured=measured
        )
        return SkillEnd(w, "done", event.describe([]), measured, events=(event,))

    def _engaged(self, state: BatchState, w: int, i: int, grip: Grip) -> Hold:
        """How the closed fingers engage object ``i``: across the pads, the longest x overlap of one of its parts
        (beside the fingers) with the pads, and the least that is a grip there (``edge_share`` of what the pads could
        cover of that part); the width between the fingers; the patch's centre from the gripper centre."""
        c = state.xpos[w, self.parts.gripper]
        lo, hi = _geom_extents(self.scene, state, w, self.parts.object_geoms[i])
        pad = 2 * self.config.finger_half[0]
        best = (0.0, 0.0, float(c[0]), float(c[2]))
        for k, g in enumerate(self.parts.object_geoms[i]):
            if self.parts.sheet[i] or _y_span_in_slab(self.scene, state, w, int(g), grip.x, grip.z) is None:
                continue
            x0, x1 = max(lo[k, 0], grip.x[0]), min(hi[k, 0], grip.x[1])
            z0, z1 = max(lo[k, 2], grip.z[0]), min(hi[k, 2], grip.z[1])
            if x1 - x0 > best[0]:
                best = (x1 - x0, self.config.edge_share * min(pad, hi[k, 0] - lo[k, 0]), (x0 + x1) / 2, (z0 + z1) / 2)
        depth, edge, x, z = best
        width = max(grip.gap, 0.0)
        if self.parts.sheet[i]:  # a fold of a sheet gathered between the pads fills them
            depth, edge, width = pad, 0.0, pad
        centre = np.array([x, (grip.left + grip.right) / 2, z]) - c
        return Hold(depth=float(depth), edge_need=float(edge), width=float(width), centre=centre)

    def _weak(self, state: BatchState, w: int, i: int, hold: Hold) -> dict[str, float]:
        """The measures of a grip on object ``i`` that cannot hold it and what is joined to it (empty if it can)."""
        carried = self._joined(state, w, int(self.scene.object_body[i]))
        bodies = np.asarray(self.scene.object_body)[carried]
        mass = self.sim.body_mass[w, bodies]
        model = self.scene.model
        com = np.array([state.xpos[w, b] + _rotation(state.xquat[w, b]) @ model.body_ipos[b] for b in bodies])
        total = mass.sum()
        centre = (com * mass[:, None]).sum(axis=0) / total if total > 0 else state.xpos[w, bodies[0]]  # (np.average's)
        weight = float(mass.sum()) * GRAVITY
        lever = centre[:2] - (state.xpos[w, self.parts.gripper] + hold.centre)[:2]
        grip = self.config.grip_force * float(contact_friction(self.config.grip_friction, self.parts.friction[i]))
        need_depth, need_width = hold.need(weight, lever, grip)
        most = 2 * grip
        if hold.depth >= need_depth - 1e-9 and hold.width >= need_width - 1e-9 and weight <= most:
            return {}
        return {
            "depth": hold.depth,
            "need_depth": need_depth,
            "edge_depth": hold.edge_need,
            "width": hold.width,
            "need_width": need_width,
            "weight": weight,
            "most_weight": most,
            "lever": float(np.linalg.norm(lever)),
            "joined": float(carried.sum() - 1),
        }

    def check_holds(self, state: BatchState, mask: np.ndarray) -> None:
        """Let go of a held object whose grip can no longer carry its load: more was joined to it, or the load the
        grasp weld carries is past what the grip holds (:meth:`_overload`)."""
        held = self._held(state, mask)
        if not held:
            return
        loads = self._loads(state, held)
        for (w, i), load in zip(held, loads, strict=True):
            hold = self._hold(w)
            weak = self._weak(state, w, i, hold)
            cause: GraspFailure = "weak_grip"
            if not weak:
                weak, cause = self._overload(w, load, hold), "slipped"
            if weak:
                self.sim.set_weld(np.array([w]), int(self.parts.grasp_eq[i]), False)
                self.state.overloaded_for[w] = 0.0
                name = self.scene.object_names[i]
                self.state.let_go[w].append(
                    Event(kind="grasp_failed", object=name, limit="grasp", cause=cause, measured=weak)
                )

    def _overload(self, w: int, load: np.ndarray, hold: Hold) -> dict[str, float]:
        """The measures of a grip in world ``w`` that cannot hold its ``load`` (:meth:`_loads`; empty while it holds):
        its force past what it holds slides the object out at once; its twist or tilt past what it holds turns the
        object in the grip, until it has been past it for ``slip_time`` in all since the grasp (a peak as a tool lands
        is ridden out, but slip adds up: a load that keeps coming back in bursts slips the grip as a steady one
        does)."""
        past = load[:3] > load[3:]
        if past[0]:
            over = 0.0  # past the pads' friction: it slides out at once
        else:
            if past[1:].any():
                self.state.overloaded_for[w] += self.scene.control_dt  # each tick past it turns it in the grip
            over = float(self.state.overloaded_for[w])
            if over < self.config.slip_time - 1e-9:
                return {}
        names = ("force", "twist", "tilt", "most_force", "most_twist", "most_tilt")
        return dict(zip(names, map(float, load), strict=True)) | {
            "depth": hold.depth,
            "width": hold.width,
            "for": over,
        }

    def _loads(self, state: BatchState, held: list[tuple[int, int]]) -> np.ndarray:
        """(k, 6) for each (world, object) in ``held``: what the object loads its grip with, then what the grip
        holds of it. The load is what the grasp weld carries, taken about the pads' patch: the force, which the
        squeeze's friction on both pads holds up to ``2 grip``; the twist about the closing axis and the tilt about
        the other two, which the pads hold up to ``slip_margin`` times the static rule's couples (``grip`` times the
        grip's depth across the pads, ``grip`` times the width between them, as :meth:`_weak` holds a static load). A
        sheet's fold bends, so it carries force only."""
        worlds = np.array([w for w, _ in held])
        objects = np.array([i for _, i in held])
        eqs = self.parts.grasp_eq[objects]
        load = np.zeros((len(held), 6))
        for eq in np.unique(eqs):
            load[eqs == eq] = self.sim.weld_load(worlds[eqs == eq], int(eq))
        force = load[:, :3]
        patch = state.xpos[worlds, self.parts.gripper] + self.state.hold_centre[worlds]
        body = state.xpos[worlds, self.scene.model.eq_obj2id[eqs]]
        torque = load[:, 3:] + np.cross(body - patch, force)
        limp = self.parts.sheet[objects]
        grip = self.config.grip_force * contact_friction(self.config.grip_friction, self.parts.friction[objects])
        couple = self.config.slip_margin * grip
        return np.column_stack(
            [
                np.linalg.norm(force, axis=1),
                np.where(limp, 0.0, np.abs(torque[:, 1])),
                np.where(limp, 0.0, np.hypot(torque[:, 0], torque[:, 2])),
                2 * grip,
                couple * self.state.hold_depth[worlds],
                couple * self.state.hold_width[worlds],
            ]
        )

    def past_capacity(self, state: BatchState) -> np.ndarray:
        """(nworld,) bool: the worlds where a held object loads the grip past what it holds (its force, twist or
        tilt; read only: :meth:`check_holds` lets go of it, at once or as the slip adds up)."""
        out = np.zeros(self.sim.nworld, dtype=bool)
        held = self._held(state, np.ones(self.sim.nworld, dtype=bool))
        if held:
            loads = self._loads(state, held)
            out[[w for w, _ in held]] = (loads[:, :3] > loads[:, 3:]).any(axis=1)
        return out

    def _hold(self, w: int) -> Hold:
        """The grip on the object held in world ``w``, as measured when it closed."""
        s = self.state
        return Hold(s.hold_depth[w], s.hold_edge[w], s.hold_width[w], s.hold_centre[w])

    def holding(self, state: BatchState, mask: np.ndarray) -> list[tuple[int, int]]:
        """(world, object) for each world in ``mask`` whose gripper holds an object (its grasp weld is on)."""
        return self._held(state, mask)

    def _held(self, state: BatchState, mask: np.ndarray) -> list[tuple[int, int]]:
        """(world, object) for each world in ``mask`` whose gripper holds an object (its grasp weld is on)."""
        objects = np.flatnonzero(self.parts.grasp_eq >= 0)
        if not objects.size:
            return []
        active = state.eq_active[:, self.parts.grasp_eq[objects]]
        return [(w, int(objects[np.argmax(active[w])])) for w in np.flatnonzero(mask & active.any(axis=1)).tolist()]

    def _resting_under(self, state: BatchState, w: int, grip: Grip) -> list[set[int]]:
        """For each finger, the graspable objects its tip rests on (under its footprint, just below it).

        Contacts report only what the tips press into; a tip resting on a top face, or on a sheet, may sit a
        hair above it, so this reads the geometry: a tip corner over the object's top, within ``on_sheet``.
        """
        out: list[set[int]] = [set(), set()]
        tips = [
            np.array([[x, y] for x in grip.x for y in ys])
            for ys in (
                (grip.left, grip.left + 2 * self.config.finger_half[1]),
                (grip.right - 2 * self.config.finger_half[1], grip.right),
            )
        ]
        for i in np.flatnonzero(self.parts.grasp_eq >= 0):
            geoms = self.parts.object_geoms[i]
            _, hi = _geom_extents(self.scene, state, w, geoms)
            for g, top in zip(geoms, hi[:, 2], strict=True):
                if not -self.config.on_top <= grip.z[0] - top <= self.config.on_sheet:
                    continue
                for f, corners in enumerate(tips):
                    if _over_geom(self.scene, state, w, int(g), corners):
                        out[f].add(int(i))
        return out

    def _fit(self, state: BatchState, w: int, i: int, grip: Grip) -> tuple[GraspFailure | None, dict[str, float]]:
        """Whether both fingers, touching object ``i``, grip it from its sides (else why not).

        Fingers that touch an object below its top and stopped apart grip it between them, if beside the
        fingers (in the slab their x and z spans make) it lies within the gap, give or take the contacts'
        give: the gap is then its width there. Beside the fingers an object that reaches further past a
        finger's inner face lies in front of, behind or under it, or (turned) across their span wider than
        their opening: pressed against its face, friction may keep the open fingers from closing, but they
        hold nothing. Fingertips at or above its
        top rest on it: it is too wide to get between the fingers, or the gripper is off to one side.
        """
        lo, hi = _geom_extents(self.scene, state, w, self.parts.object_geoms[i])
        near = (lo[:, 0] < grip.x[1] + self.config.grip_tolerance) & (hi[:, 0] > grip.x[0] - self.config.grip_tolerance)
        if not near.any():
            return "not_between", {}
        lo, hi = lo[near], hi[near]
        if self.parts.sheet[i]:  # fingertips pressed on a sheet pinch a fold of it
            return None, {"width": 2 * min(self.scene.task.objects[i].size), "opening": self.limits.gripper_opening}
        if grip.z[0] > hi[:, 2].max() - self.config.on_top:
            width = float((hi[:, 1] - lo[:, 1]).min())
            return ("too_wide" if width > self.limits.gripper_opening else "on_top"), {
                "width": width,
                "opening": self.limits.gripper_opening,
            }
        spans = [_y_span_in_slab(self.scene, state, w, int(g), grip.x, grip.z) for g in self.parts.object_geoms[i]]
        inside = np.array([s for s in spans if s is not None]).reshape(-1, 2)  # its y spans beside the fingers
        between = (inside[:, 0] < grip.left) & (inside[:, 1] > grip.right)  # some of it lies between the fingers
        if grip.gap <= 0.0 or not between.any():
            return "not_between", {}
        if (
            grip.gap > self.limits.gripper_opening + self.config.opening_give
        ):  # wedged in, it pushed the open fingers apart
            return "too_wide", {"width": grip.gap, "opening": self.limits.gripper_opening}
        low, high = float(inside[:, 0].min()), float(inside[:, 1].max())
        if low < grip.right - self.config.side_slack or high > grip.left + self.config.side_slack:
            # beside the fingers it reaches past one of them: they pressed on a face in front of (or behind or
            # under) them, not on its sides
            return "not_between", {"span": high - low, "gap": grip.gap}
        return None, {"width": grip.gap, "opening": self.limits.gripper_opening}

    def _nearest(self, state: BatchState, w: int) -> tuple[int, dict[str, float]]:
        """The graspable object whose graspable point is nearest to the gripper centre, and that distance."""
        candidates = np.flatnonzero(self.parts.grasp_eq >= 0)
        if not candidates.size:
            return -1, {}
        points = graspable_points(self.scene, state)[w, candidates]
        dist = np.linalg.norm(points - state.xpos[w, self.parts.gripper], axis=1)
        return int(candidates[np.argmin(dist)]), {"nearest": float(dist.min())}


def _geom_pose(scene: Scene, state: BatchState, w: int, geom: int) -> tuple[np.ndarray, np.ndarray]:
    """World rotation (3, 3) and centre (3,) of a geom in world ``w``, from its body's pose in the state."""
    model = scene.model
    body = model.geom_bodyid[geom]
    body_rot = _rotation(state.xquat[w, body])
    return body_rot @ _rotation(model.geom_quat[geom]), state.xpos[w, body] + body_rot @ model.geom_pos[geom]


def _rotation(quat: np.ndarray) -> np.ndarray:
    """The rotation matrix (3, 3) of a unit quaternion (w, x, y, z)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(quat, dtype=float))
    return rot.reshape(3, 3)


def _over_geom(scene: Scene, state: BatchState, w: int, geom: int, points: np.ndarray) -> bool:
    """Whether any of the x-y ``points`` lies over the footprint of a box or upright cylinder geom in world ``w``."""
    model = scene.model
    rot, centre = _geom_pose(scene, state, w, geom)
    local = (np.column_stack([points, np.full(len(points), centre[2])]) - centre) @ rot
    size = model.geom_size[geom]
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return bool(np.any(np.hypot(local[:, 0], local[:, 1]) <= size[0]))
    return bool(np.any(np.all(np.abs(local[:, :2]) <= size[:2], axis=1)))


def _y_span_in_slab(
    scene: Scene,
    state: BatchState,
    w: int,
    geom: int,
    x: tuple[float, float],
    z: tuple[float, float],
    sides: int = ARM.slab_cylinder_sides,
) -> tuple[float, float] | None:
    """Lowest and highest world y of a box or cylinder geom's volume within ``x`` and ``z`` (any y) in world
    ``w``, or None where it misses that slab: the extremes of a convex polytope, found among its vertices (a
    cylinder counts as the prism of ``sides`` sides around it)."""
    model = scene.model
    rot, centre = _geom_pose(scene, state, w, geom)
    size = model.geom_size[geom]
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        turn = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
        local = np.column_stack([np.cos(turn), np.sin(turn), np.zeros_like(turn)])
        local = np.vstack([local, [[0, 0, 1], [0, 0, -1]]])
        reach = np.concatenate([np.full(sides, size[0]), [size[1], size[1]]])
    else:
        local = np.vstack([np.eye(3), -np.eye(3)])
        reach = np.concatenate([size[:3], size[:3]])
    normals = local @ rot.T  # outward face normals in the world: normal . p <= normal . centre + reach
    offsets = normals @ centre + reach
    slab = np.array([[-1.0, 0, 0], [1, 0, 0], [0, 0, -1], [0, 0, 1]])
    normals = np.vstack([normals, slab])
    offsets = np.concatenate([offsets, [-x[0], x[1], -z[0], z[1]]])
    triples = np.array(list(combinations(range(len(normals)), 3)))
    planes = normals[triples]
    solvable = np.abs(np.linalg.det(planes)) > 1e-12
    corners = np.linalg.solve(planes[solvable], offsets[triples[solvable]][..., None])[..., 0]
    corners = corners[np.all(corners @ normals.T <= offsets + 1e-9, axis=1)]
    if not len(corners):
        return None
    return float(corners[:, 1].min()), float(corners[:, 1].max())


def _geom_extents(scene: Scene, state: BatchState, w: int, geoms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World axis-aligned bounds (low, high), (ngeom, 3) each, of box and cylinder geoms in world ``w``."""
    model = scene.model
    lo, hi = np.zeros((len(geoms), 3)), np.zeros((len(geoms), 3))
    for k, g in enumerate(geoms):
        rot, centre = _geom_pose(scene, state, w, g)
        size = model.geom_size[g]
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER:
            axis = np.abs(rot[:, 2])
            half = axis * size[1] + size[0] * np.sqrt(np.clip(1 - axis**2, 0, 1))
        else:
            half = np.abs(rot) @ size
        lo[k], hi[k] = centre - half, centre + half
    return lo, hi
