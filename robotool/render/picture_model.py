"""The model pictures are drawn from: the task's model with colours, a floor grid, a sky and goal markers.

It is compiled from the same :func:`robotool.sim.build.make_spec` as the simulated model and only adds
visual elements (textures, materials, lights and contact-free marker geoms on the world body), so bodies
and joints keep their indices and a simulated ``qpos`` can be shown as it is. The simulated model is
never changed.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool import robots
from robotool.sim.build import embodiment_for, make_spec
from robotool.sim.compiled_scene import Scene
from robotool.task import geometry
from robotool.task.task_model import Task

ROBOT_RGBA = (0.93, 0.45, 0.10, 1.0)
FIXED_RGBA = (0.62, 0.55, 0.48, 1.0)  # furniture and other fixed objects
GOAL_RGBA = (0.20, 0.75, 0.30, 1.0)  # the object the goal is about
MARKER_RGBA = (0.20, 0.75, 0.30, 0.35)  # translucent goal-height plane
# Movable objects, in order (colour-blind-friendly hues, none close to the robot's or the goal's).
PALETTE = (
    (0.12, 0.47, 0.71, 1.0),
    (0.80, 0.47, 0.74, 1.0),
    (0.94, 0.89, 0.26, 1.0),
    (0.35, 0.71, 0.91, 1.0),
    (0.55, 0.34, 0.29, 1.0),
    (0.58, 0.40, 0.74, 1.0),
    (0.84, 0.15, 0.16, 1.0),
    (0.50, 0.50, 0.50, 1.0),
)
MARKER_HALF_THICKNESS = 0.001  # m
MARKER_MARGIN = 0.2  # m the goal-height plane reaches beyond the goal object's footprint
SHADOW_MAP = 2048  # px, side of the shadow map


@dataclass(frozen=True)
class RenderModel:
    """A compiled model for drawing one scene, and what each object looks like in it."""

    scene: Scene
    model: mujoco.MjModel
    object_rgba: tuple[tuple[float, float, float, float], ...]
    goal_marker_height: float | None  # m: height of the drawn goal plane (lifted / lowered goals)


def object_colours(task: Task) -> tuple[tuple[float, float, float, float], ...]:
    """Colour of each task object: the goal's object green, fixed ones beige, movable ones from the palette."""
    colours = []
    movable = 0
    for obj in task.objects:
        if obj.name == task.goal.object:
            colours.append(GOAL_RGBA)
        elif not obj.movable:
            colours.append(FIXED_RGBA)
        else:
            colours.append(PALETTE[movable % len(PALETTE)])
            movable += 1
    return tuple(colours)


def _goal_height(scene: Scene) -> float | None:
    goal = scene.task.goal
    if goal.lifted is not None:
        return goal.lifted.height
    if goal.lowered is not None:
        return goal.lowered.height
    return None


def _decorate(spec: mujoco.MjSpec, scene: Scene, marker_height: float | None, shadows: bool) -> None:
    """Floor grid, sky gradient, lights and the goal-height plane."""
    spec.visual.global_.offwidth = 1920
    spec.visual.global_.offheight = 1080
    spec.visual.quality.shadowsize = SHADOW_MAP if shadows else 0
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.45, 0.45, 0.45]
    spec.add_texture(
        name="sky",
        type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
        rgb1=[0.85, 0.90, 0.95],
        rgb2=[0.55, 0.65, 0.75],
        width=256,
        height=256,
    )
    spec.add_texture(
        name="floor",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        rgb1=[0.82, 0.82, 0.80],
        rgb2=[0.74, 0.74, 0.72],
        mark=mujoco.mjtMark.mjMARK_EDGE,
        markrgb=[0.6, 0.6, 0.6],
        width=512,
        height=512,
    )
    square = robots.get(scene.task.embodiment).pictures.view.floor_square  # m, for scale
    floor = spec.add_material(name="floor", texrepeat=[1 / (2 * square)] * 2, texuniform=True)
    floor.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "floor"
    ground = spec.geom("ground")
    if ground is not None:
        ground.material = "floor"
    spec.worldbody.add_light(
        name="sun",
        pos=[0, 0, 4],
        dir=[0.3, 0.2, -1],
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        castshadow=True,
        diffuse=[0.6, 0.6, 0.6],
        specular=[0.1, 0.1, 0.1],
    )
    if marker_height is not None:
        lo, hi = _goal_object_xy_bounds(scene)
        half = (hi - lo) / 2 + MARKER_MARGIN
        centre = (lo + hi) / 2
        spec.worldbody.add_geom(
            name="render_goal_height",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[half[0], half[1], MARKER_HALF_THICKNESS],
            pos=[centre[0], centre[1], marker_height],
            rgba=list(MARKER_RGBA),
            contype=0,
            conaffinity=0,
        )


def _goal_object_xy_bounds(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The goal object's footprint in the plane at the start (min, max), m."""
    obj = scene.task.object(scene.task.goal.object)
    corners = np.array([c for p in geometry.object_parts(obj) for c in p.aabb()])
    return corners[:, :2].min(axis=0), corners[:, :2].max(axis=0)


def render_model(scene: Scene, *, shadows: bool = True) -> RenderModel:
    """Compile the drawing model of ``scene`` and colour its geoms by what they belong to.

    Without ``shadows`` each frame takes about half the time on a software renderer (for videos).
    """
    marker = _goal_height(scene)
    spec = make_spec(scene.task, embodiment_for(scene.task))
    _decorate(spec, scene, marker, shadows)
    model = spec.compile()
    if model.nq != scene.model.nq or model.nbody != scene.model.nbody:
        raise RuntimeError("the drawing model does not match the simulated one")
    colours = object_colours(scene.task)
    for g in range(model.ngeom):
        body = model.geom_bodyid[g]
        if body == 0 or model.geom_rgba[g, 3] == 0:  # invisible helpers (a sheet's carriers) stay unseen
            continue
        obj = scene.body_object[body]
        if obj >= 0:
            face = model.body(body).name.endswith("__face")  # a button's face keeps its own colour
            if not face:
                model.geom_rgba[g] = colours[obj]
        elif scene.robot_body[body]:
            model.geom_rgba[g] = ROBOT_RGBA
    return RenderModel(scene=scene, model=model, object_rgba=colours, goal_marker_height=marker)
