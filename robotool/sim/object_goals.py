"""The object goal kinds that any robot may be given, as named sub-conditions: ``lifted`` and ``lowered``.

Object extents come from the state: every object carries the corners of its parts in its body
frame, placed each tick by its body pose; an object's bottom is read from its parts' own shapes (a box's lowest
corner, a cylinder's lowest rim point: :class:`Underside`), not from the corners of a cylinder's bounding box, which
a rolled cylinder turns below its round side. A fragile object's falls are followed every control tick:
a fall starts where it was last resting (touching something, the robot too, nearly still; or held in the robot's
grip, at any speed) or from the highest point it rose to since (a tossed object falls from the top of its flight), and
lasts until it rests again; it breaks once it touches something hard (not soft, not the robot) with
its centre more than ``max_drop`` below where it rested, or once the robot or a movable object that is not soft comes
to touch it faster than such a fall lands (:mod:`robotool.sim.strikes`). A soft object it glances off on the way, or
a wall it grazes, does not end the fall, and neither does the tick at which contacts happen to be
read: once a fall could pass ``max_drop`` before the next tick, every physics step of that interval is read, so a
hard strike that begins and ends between two ticks breaks it too. The first breaking fall of each world is kept as a
``broke`` event.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.rollout import Event
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import ReadAtTicks
from robotool.sim.strikes import GeomFrames, StrikeWatch, geom_half_sizes
from robotool.task import geometry
from robotool.task.scene import SceneObject
from robotool.task.task_file import RESTING_TOLERANCE

RESTING_SPEED = 0.05  # m/s: slower than this while supported is resting
WELD, BODY = int(mujoco.mjtEq.mjEQ_WELD), int(mujoco.mjtObj.mjOBJ_BODY)
FALL_ACCELERATION = 2 * 9.81  # m/s^2: the most a falling object is taken to gain downward speed by (gravity, twice)
RIM_POINTS = 12  # points read round each rim of a cylinder for how fast its outline comes down
TOUCH_BAND = 0.02  # m: a point of an outline this close to a body's geom (its box) may be what touched it


def local_corners(scene: Scene) -> list[np.ndarray]:
    """Per object, the corners (k, 3) of its parts in its body frame."""
    out = []
    for obj in scene.task.objects:
        rot = geometry.rotation_matrix(obj.rpy)
        corners = np.vstack([p.corners() for p in geometry.object_parts(obj)])
        out.append((corners - np.asarray(obj.center)) @ rot)
    return out


def world_corners(state: BatchState, body: int, local: np.ndarray) -> np.ndarray:
    """Corners (nworld, k, 3) of one object in the world."""
    return state.xpos[:, body, None, :] + np.einsum("wij,kj->wki", state.xmat(body), local)


@dataclass(frozen=True)
class Underside:
    """What an object's lowest point is read from, in its body frame: its box parts' corners and its cylinder
    parts' centres, unit axes, radii and half-lengths."""

    corners: np.ndarray  # (k, 3)
    centres: np.ndarray  # (m, 3)
    axes: np.ndarray  # (m, 3)
    radius: np.ndarray  # (m,)
    half_length: np.ndarray  # (m,)

    @classmethod
    def of(cls, obj: SceneObject) -> Underside:
        """Read from a task object's parts, in the frame of its body (its centre and rotation)."""
        return cls.of_parts(geometry.object_parts(obj), np.asarray(obj.center), geometry.rotation_matrix(obj.rpy))

    @classmethod
    def of_body(cls, model: mujoco.MjModel, body: int) -> Underside:
        """Read from the box and cylinder geoms of one ``body`` of a compiled model (a cloth's link), in its frame."""
        parts = []
        for g in np.flatnonzero(model.geom_bodyid == body):
            frame = np.zeros(9)
            mujoco.mju_quat2Mat(frame, model.geom_quat[g])
            size = model.geom_size[g]
            if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
                parts.append(geometry.Part("box", model.geom_pos[g], size.copy(), frame.reshape(3, 3)))
            elif model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER:  # MuJoCo's size: radius, half-length
                half = np.array([size[0], size[0], size[1]])
                parts.append(geometry.Part("cylinder", model.geom_pos[g], half, frame.reshape(3, 3)))
        return cls.of_parts(parts, np.zeros(3), np.eye(3))

    @classmethod
    def of_parts(cls, parts: list[geometry.Part], centre: np.ndarray, rot: np.ndarray) -> Underside:
        """Read from ``parts`` given in the world, in the frame whose origin is ``centre`` and rotation ``rot``."""
        boxes = [p for p in parts if p.kind == "box"]
        cylinders = [p for p in parts if p.kind == "cylinder"]
        return cls(
            corners=(np.vstack([p.corners() for p in boxes]) - centre) @ rot if boxes else np.zeros((0, 3)),
            centres=np.array([(p.center - centre) @ rot for p in cylinders]).reshape(-1, 3),
            axes=np.array([p.rot[:, 2] @ rot for p in cylinders]).reshape(-1, 3),
            radius=np.array([p.half[0] for p in cylinders]),
            half_length=np.array([p.half[2] for p in cylinders]),
        )

    def rims(self, points: int = RIM_POINTS) -> np.ndarray:
        """(k, 3) points on the object's outline in its body frame: its boxes' corners and ``points`` points round
        each rim of its cylinders."""
        angle = np.linspace(0.0, 2 * np.pi, points, endpoint=False)
        rims = []
        for centre, axis, radius, half in zip(self.centres, self.axes, self.radius, self.half_length, strict=True):
            side = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
            side /= np.linalg.norm(side)
            ring = radius * (np.cos(angle)[:, None] * side + np.sin(angle)[:, None] * np.cross(axis, side))
            rims += [centre + end * half * axis + ring for end in (-1.0, 1.0)]
        return np.vstack([self.corners, *rims])

    def bottom(self, state: BatchState, body: int) -> np.ndarray:
        """(nworld,) the height of the object's lowest point in each world: a cylinder whose axis makes an angle
        with the vertical whose cosine is c reaches ``half_length * |c| + radius * sqrt(1 - c^2)`` below its centre."""
        lowest = world_corners(state, body, self.corners)[:, :, 2].min(axis=1, initial=np.inf)
        if not len(self.radius):
            return lowest
        frame = state.xmat(body)  # (nworld, 3, 3)
        centre_z = state.xpos[:, body, None, 2] + np.einsum("wj,kj->wk", frame[:, 2, :], self.centres)
        c = np.einsum("wj,kj->wk", frame[:, 2, :], self.axes)  # (nworld, m): each axis's vertical part
        reach = self.half_length * np.abs(c) + self.radius * np.sqrt(np.maximum(0.0, 1.0 - c * c))
        return np.minimum(lowest, (centre_z - reach).min(axis=1))


@dataclass(frozen=True)
class ObjectBottom:
    """An object's lowest point over all its bodies: one for a rigid object (read from its parts), each link of a
    cloth (read from the link's own geom, where that link lies: a cloth hanging over a table's edge is not one rigid
    box placed at its first link)."""

    parts: tuple[tuple[int, Underside], ...]

    @classmethod
    def of(cls, scene: Scene, index: int) -> ObjectBottom:
        bodies = np.flatnonzero(scene.body_object == index)
        if len(bodies) == 1:
            return cls(((int(bodies[0]), Underside.of(scene.task.objects[index])),))
        return cls(tuple((int(b), Underside.of_body(scene.model, int(b))) for b in bodies))

    def height(self, state: BatchState) -> np.ndarray:
        """(nworld,) the height of the object's lowest point in each world."""
        return np.min([underside.bottom(state, body) for body, underside in self.parts], axis=0)


class LiftedGoal(ReadAtTicks):
    """``lifted: {object, height}``: the object's bottom is at least ``height`` above its start: where it lies when the
    program starts, or where the task file puts it when that is more than :data:`RESTING_TOLERANCE` higher (found by
    an adversarial run: a block placed with 8 mm of its base on a shelf tipped off it while the world settled, and a
    lift from the floor counted from there)."""

    def __init__(self, scene: Scene):
        goal = scene.task.goal.lifted
        assert goal is not None
        self.name, self.height = goal.object, goal.height
        self.bottom = ObjectBottom.of(scene, scene.object_index(self.name))
        self.stated = scene.task.object(self.name).bottom - RESTING_TOLERANCE
        self.start: np.ndarray | None = None

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        if self.start is None:
            self.start = np.maximum(self._bottom(state), self.stated)

    def _bottom(self, state: BatchState) -> np.ndarray:
        return self.bottom.height(state)

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        start = self.start if self.start is not None else self._bottom(state)
        return {f"{self.name}_lifted": self._bottom(state) - start >= self.height}


class FallTracker:
    """Follows the falls of one fragile object in every world and remembers whether it broke. A fixed one does not
    fall or land: it breaks where something strikes it too fast (:class:`~robotool.sim.strikes.StrikeWatch`)."""

    def __init__(self, scene: Scene, sim: BatchedSim, index: int, max_drop: float):
        self.scene, self.max_drop = scene, max_drop
        self.body = scene.object_body[index]
        self.bodies = np.flatnonzero(scene.body_object == index)
        others = ~np.isin(np.arange(scene.model.nbody), self.bodies) & ~scene.robot_body
        self.others = np.flatnonzero(others)  # the bodies that can carry it or that it can strike
        soft = np.array([o.soft for o in scene.task.objects])
        owner = scene.body_object[self.others]
        self.hard = (owner < 0) | ~soft[np.maximum(owner, 0)]  # per body in ``others``: the ground or not soft
        self.robot = np.flatnonzero(scene.robot_body)
        model = scene.model
        ends = np.stack([model.eq_obj1id, model.eq_obj2id], axis=1)
        mine, robots = np.isin(ends, self.bodies), scene.robot_body[ends]
        bodies = (model.eq_type == WELD) & (model.eq_objtype == BODY)
        self.grips = np.flatnonzero(bodies & (mine & robots[:, ::-1]).any(axis=1))  # welds to the robot: its grip
        self.rest_height: np.ndarray | None = None
        self.broken: np.ndarray | None = None
        self.breaks: dict[int, Event] = {}
        self.name = scene.task.objects[index].name
        self.strikes = StrikeWatch(scene, sim, index, max_drop)
        self.landings = OutlineLandings(scene, index, max_drop, self.strikes.limit, self.others)
        self.moves = not self.strikes.fixed_object
        self._touch = np.zeros((0, len(self.others)), dtype=bool)  # (nworld, len(others)) at the last reading

    def update(self, state: BatchState, active: np.ndarray) -> None:
        touch = np.any(state.touching[:, self.bodies][:, :, self.others], axis=1)  # (nworld, len(others))
        height = state.xpos[:, self.body, 2]
        if self.rest_height is None:
            self.rest_height = height.copy()
            self.broken = np.zeros(height.shape, dtype=bool)
            self._touch = touch
        assert self.broken is not None
        self.rest_height = np.where(active, np.maximum(self.rest_height, height), self.rest_height)  # from the top
        fall = self.rest_height - height  # read before this tick's rest: a landing that stops dead still fell
        hard = touch & self.hard
        struck = active & hard.any(axis=1) & (fall > self.max_drop) & ~self.broken
        for w in map(int, np.flatnonzero(struck)):
            measured = {"fall": float(fall[w]), "max_drop": self.max_drop}
            self._break(state, w, measured, self._names(self.scene.body_object[self.others[hard[w]]]))
        speed, strikers, through = self.strikes.update(state, active)
        for w in map(int, np.flatnonzero(active & (speed > self.strikes.limit) & ~self.broken)):
            names = sorted({self.strikes.name(k, int(through[w, k])) for k in np.flatnonzero(strikers[w]).tolist()})
            self._break(state, w, self._strike(float(speed[w])), " and ".join(names))
        if self.moves:
            new = active[:, None] & hard & ~self._touch  # (a body at a time: what it touched already is not landed on)
            landing, onto = self.landings.landing(state, active, new)
            for w in map(int, np.flatnonzero(active & (landing > self.strikes.limit) & ~self.broken)):
                landed_on = self._names(self.scene.body_object[self.others[onto[w]]])
                self._break(state, w, self._strike(float(landing[w])), landed_on)
        self._touch = np.where(active[:, None], touch, self._touch)
        speed = np.abs(self.strikes.own_velocity(state)).max(axis=1)
        held = self._held(state)
        borne = touch.any(axis=1) | state.touching[:, self.bodies][:, :, self.robot].any(axis=(1, 2))
        resting = active & (held | (borne & (speed < RESTING_SPEED)))
        self.rest_height = np.where(resting, height, self.rest_height)
        if self.moves:
            self.landings.rest(resting)

    def _break(self, state: BatchState, world: int, measured: dict[str, float], detail: str) -> None:
        """It broke in ``world`` now: keep the ``broke`` event."""
        assert self.broken is not None
        self.broken[world] = True
        event = Event(kind="broke", time=float(state.time[world]), object=self.name, measured=measured, detail=detail)
        self.breaks[world] = event

    def _strike(self, speed: float) -> dict[str, float]:
        """What a strike (or a landing) at ``speed`` m/s measured."""
        return {"strike_speed": speed, "max_speed": self.strikes.limit, "max_drop": self.max_drop}

    def unbroken(self, nworld: int) -> np.ndarray:
        """(nworld,) bool: the worlds in which it has not broken."""
        return ~self.broken if self.broken is not None else np.ones(nworld, dtype=bool)

    def events(self, world: int) -> list[Event]:
        """The world's ``broke`` event, if it broke (time in the simulator's clock)."""
        event = self.breaks.get(world)
        return [] if event is None else [event]

    def watched(self, state: BatchState) -> np.ndarray:
        """(nworld,) the unbroken worlds where the object could fall past ``max_drop`` before the next tick (its fall
        so far, plus what its downward speed and :data:`FALL_ACCELERATION` add in a control interval, passes it), a
        point of its outline not in the robot's grip could come down faster than the limit by then, or it could
        be struck too fast (:meth:`~robotool.sim.strikes.StrikeWatch.watched`)."""
        if self.rest_height is None or self.broken is None:
            return np.zeros(len(state.time), dtype=bool)
        dt = self.scene.control_dt
        held = self._held(state)
        if not self.moves:
            return ~self.broken & self.strikes.watched(state, dt, held)
        fall = self.rest_height - state.xpos[:, self.body, 2]
        sinking = np.maximum(-self.strikes.own_velocity(state)[:, 2], 0.0)
        falling = fall + sinking * dt + FALL_ACCELERATION * dt**2 / 2 > self.max_drop
        landing = ~held & (self.landings.descent(state).max(axis=1) + FALL_ACCELERATION * dt > self.strikes.limit)
        return ~self.broken & (falling | landing | self.strikes.watched(state, dt, held))

    def _held(self, state: BatchState) -> np.ndarray:
        """(nworld,) whether it is in the robot's grip, where it moves with the hand."""
        return np.asarray(state.eq_active[:, self.grips].any(axis=1))

    def _names(self, objects: np.ndarray) -> str:
        """What a fall landed on: object names, or the ground for the world's own bodies."""
        names = sorted({self.scene.task.objects[k].name if k >= 0 else "the ground" for k in objects.tolist()})
        return " and ".join(names) if names else "the ground"


class OutlineLandings:
    """How the outline of one fragile object lands (:class:`FallTracker` reads its centre's falls): a tall glass column
    knocked over lands on its top's edge at about sqrt(3 g L), though its centre drops less than ``max_drop`` (found
    by an adversarial run). Each point of its outline (its boxes' corners, points round its cylinders' rims) falls, like
    the centre, from where it last rested or the highest it rose to since; where the object comes to touch something
    hard (the ground too), a point near it that fell more than ``max_drop`` and came down faster than such a fall
    lands (at this reading or the last) lands on it. A rolling object comes down at no point where it meets the ground,
    and a wobble lifts a point less than any fall that breaks."""

    def __init__(self, scene: Scene, index: int, max_drop: float, limit: float, bodies: np.ndarray):
        self.body, self.max_drop, self.limit, self.bodies = int(scene.object_body[index]), max_drop, limit, bodies
        self.model, self.half = scene.model, geom_half_sizes(scene.model)
        self.dof = int(scene.model.body_dofadr[self.body])  # its free joint: linear (world), then angular (own frame)
        self.outline = Underside.of(scene.task.objects[index]).rims()  # (k, 3) in its body's frame
        self.rest_heights = np.zeros((0, len(self.outline)))  # (nworld, k) where each point fell from
        self._descent = np.zeros((0, len(self.outline)))  # (nworld, k) how fast each came down at the last reading
        self._heights = np.zeros((0, len(self.outline)))  # (nworld, k) each point's height at this reading

    def landing(self, state: BatchState, active: np.ndarray, new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Read the ``active`` worlds (each point falls from the highest it rose to) and where the object came to
        touch bodies ``new`` (nworld, len(bodies)) anew: (nworld,) the speed the fastest of its points that fell more
        than ``max_drop`` came down at, of those within :data:`TOUCH_BAND` of such a body (0 elsewhere), and
        (nworld, len(bodies)) which bodies they landed on. The descent is remembered in every world. A point high in
        the air lands on nothing: a column pivoting on its stool touches the stool anew each time the pivot's contact
        flickers while its top is still falling (a false alarm an adversarial run found: the top then landed on a soft
        cushion)."""
        descent, points = self.descent(state), world_corners(state, self.body, self.outline)
        self._heights = points[:, :, 2]
        if len(self.rest_heights) != len(points):
            self.rest_heights, self._descent = self._heights, descent
        self.rest_heights = np.where(active[:, None], np.maximum(self.rest_heights, self._heights), self.rest_heights)
        coming = np.maximum(descent, self._descent)
        self._descent = descent
        fast = (self.rest_heights - self._heights > self.max_drop) & (coming > self.limit)
        speed, onto = np.zeros(len(points)), np.zeros(new.shape, dtype=bool)
        for w in map(int, np.flatnonzero(new.any(axis=1) & fast.any(axis=1))):
            for j in map(int, np.flatnonzero(new[w])):
                near = self._near(state, w, int(self.bodies[j]), points[w, fast[w]])
                if near.any():
                    onto[w, j] = True
                    speed[w] = max(speed[w], float(coming[w, fast[w]][near].max()))
        return speed, onto

    def _near(self, state: BatchState, world: int, body: int, points: np.ndarray) -> np.ndarray:
        """(m,) which ``points`` (m, 3) lie within :data:`TOUCH_BAND` of a geom of ``body`` in ``world`` (its box, or
        above a plane)."""
        near = np.zeros(len(points), dtype=bool)
        geoms = np.flatnonzero(self.model.geom_bodyid == body)
        centres, frames = GeomFrames.of(self.model, geoms).poses(state)
        for k, g in enumerate(geoms.tolist()):
            local = (points - centres[world, k]) @ frames[world, k]
            if self.model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE:
                near |= local[:, 2] <= TOUCH_BAND
            else:
                near |= (np.abs(local) <= self.half[g] + TOUCH_BAND).all(axis=1)
        return near

    def rest(self, resting: np.ndarray) -> None:
        """The ``resting`` worlds: each point falls from where it was at the last :meth:`landing` reading."""
        self.rest_heights = np.where(resting[:, None], self._heights, self.rest_heights)

    def descent(self, state: BatchState) -> np.ndarray:
        """(nworld, k) how fast each point of the outline comes down (0: it does not)."""
        frame = state.xmat(self.body)
        offset = np.einsum("wij,kj->wki", frame, self.outline)  # each point from the body's origin
        spin = np.einsum("wij,wj->wi", frame, state.qvel[:, self.dof + 3 : self.dof + 6])
        up = state.qvel[:, None, self.dof + 2] + spin[:, None, 0] * offset[:, :, 1] - spin[:, None, 1] * offset[:, :, 0]
        return np.maximum(-up, 0.0)


class LoweredGoal(ReadAtTicks):
    """``lowered: {object, height}``: bottom at most ``height`` above the ground (a fragile object must also end
    unbroken, as every fragile object must: :class:`robotool.sim.goals.WithSceneRules`)."""

    def __init__(self, scene: Scene):
        goal = scene.task.goal.lowered
        assert goal is not None
        self.name, self.height = goal.object, goal.height
        self.bottom = ObjectBottom.of(scene, scene.object_index(self.name))

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        """Nothing to remember: the goal holds at the end."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        return {f"{self.name}_lowered": self.bottom.height(state) <= self.height}
