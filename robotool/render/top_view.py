"""A top-down plan of one world's rollout (matplotlib, no OpenGL): footprints, the robot's path, pushes, refusals.

Objects are drawn as their footprints with their names and top heights, the goal's object in green. Each
motion skill becomes an arrow: skills that move the robot (one position argument) from where the robot was
to the target, skills that move an object (an object name and a position) from the object to the target.
Arrows of skills that ended ``done`` are solid; refused, stalled or timed-out ones are red and dashed, a cross
where the robot stopped and the reason written there. Objects that moved are drawn again, dashed, where they
ended, and the robot where it ended. With a recorded track the robot's actual path is drawn too, failed moves
start where the robot really was, and the end poses are the simulated ones (else: the targets of the skills
that ended ``done``). Labels never overlap: each is moved, by as little as it takes, off the ones placed before.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path

import mujoco
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon, Rectangle
from matplotlib.text import Annotation

from robotool import robots
from robotool.render.picture_model import GOAL_RGBA, ROBOT_RGBA, object_colours
from robotool.rollout import Rollout, SkillCall
from robotool.safe_text import capped, plot_text
from robotool.sim.compiled_scene import Scene
from robotool.sim.recorder import Track
from robotool.task import geometry
from robotool.task.task_model import Task

Colour = str | tuple[float, ...]
REFUSED = "#d62728"
PUSH = "#1f77b4"
ROBOT = ROBOT_RGBA[:3]
MIN_ARROW = 0.01  # m: shorter moves in the plane are not drawn
REASON_CHARS = 60  # a refusal reason is cut to this many characters on the plan


def _footprint(task: Task, index: int) -> list[np.ndarray]:
    """The xy outline (n, 2) of each of an object's parts (a hook is two)."""
    return [_convex_hull(p.corners()[:, :2]) for p in geometry.object_parts(task.objects[index])]


def _convex_hull(points: np.ndarray) -> np.ndarray:
    """Andrew's monotone chain: the hull of 2-D points, counter-clockwise."""
    pts = sorted({(round(float(x), 6), round(float(y), 6)) for x, y in points})
    if len(pts) < 3:
        return np.array(pts)

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for p in seq:
            while (
                len(out) >= 2
                and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]))
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def robot_path(scene: Scene, track: Track) -> tuple[np.ndarray, np.ndarray]:
    """(times (T,), xy (T, 2)) of the robot's root body over a recorded track."""
    model = scene.model
    data = mujoco.MjData(model)
    root = int(np.flatnonzero(scene.robot_body)[0])
    times, qpos, _ = track.arrays()
    xy = np.zeros((len(times), 2))
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        xy[k] = data.xpos[root, :2]
    return times, xy


def _position_at(times: np.ndarray, xy: np.ndarray, t: float) -> np.ndarray:
    return np.array([np.interp(t, times, xy[:, 0]), np.interp(t, times, xy[:, 1])])


def plan_figure(task: Task, rollout: Rollout, *, scene: Scene | None = None, track: Track | None = None) -> Figure:
    """The plan of ``rollout`` in ``task`` as a matplotlib figure (``scene`` and ``track`` add the real path)."""
    fig = Figure(figsize=(8, 5.5), dpi=110)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    colours = object_colours(task)
    centres: dict[str, np.ndarray] = {}
    outlines = [_footprint(task, i) for i in range(len(task.objects))]
    for i, obj in enumerate(task.objects):
        goal = obj.name == task.goal.object
        for outline in outlines[i]:
            ax.add_patch(
                Polygon(
                    outline,
                    closed=True,
                    facecolor=colours[i][:3],
                    alpha=0.35 if obj.movable else 0.5,
                    edgecolor="black",
                    linewidth=1.6 if goal else 0.8,
                )
            )
        centres[obj.name] = np.asarray(obj.center[:2], dtype=float)
        ax.annotate(
            f"{plot_text(obj.name)}{' (goal)' if goal else ''}\ntop {obj.top:.2f} m",
            _xy(centres[obj.name]),
            xytext=(0, 0),
            textcoords="offset points",
            fontsize=7,
            ha="center",
            va="center",
            color="darkgreen" if goal else "black",
            bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "alpha": 0.6, "linewidth": 0},
        )
    path_times, path_xy = robot_path(scene, track) if scene is not None and track is not None else (None, None)
    start = _start(task, path_xy)
    _draw_robot_box(ax, task, start)
    if path_xy is not None:
        ax.plot(path_xy[:, 0], path_xy[:, 1], color=ROBOT, linewidth=1.2, alpha=0.8, label="robot path (simulated)")
    starts = dict(centres)
    robot_end = _draw_calls(ax, task, rollout, start, centres, path_times, path_xy)
    if scene is not None and track is not None:
        ends = _simulated_ends(scene, track)
        robot_end = path_xy[-1] if path_xy is not None else robot_end
    else:
        ends = {name: (at, np.eye(2)) for name, at in centres.items()}
    _draw_ends(ax, task, outlines, starts, ends, colours)
    if np.linalg.norm(robot_end - start) >= MIN_ARROW:
        _draw_robot_box(ax, task, robot_end, end=True)
    verdict = "goal reached" if rollout.success else "goal not reached"
    ax.set_title(
        plot_text(f"{task.name}, world {rollout.world}: {task.goal.text()} - {verdict}"),
        fontsize=9,
        color=tuple(GOAL_RGBA[:3]) if rollout.success else REFUSED,
    )
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.08)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    with _without_glyph_warnings():
        fig.tight_layout()
        _declutter(canvas, ax)
    return fig


def _simulated_ends(scene: Scene, track: Track) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each object's xy at the end of the track, and its turn in the plane since the start (2x2)."""
    model = scene.model
    data = mujoco.MjData(model)
    _, qpos, _ = track.arrays()
    frames = []
    for q in (model.qpos0, qpos[-1]):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        frames.append((data.xpos.copy(), data.xmat.reshape(-1, 3, 3).copy()))
    (_, start_rot), (end_pos, end_rot) = frames
    ends = {}
    for i, name in enumerate(scene.object_names):
        body = int(scene.object_body[i])
        ends[name] = (end_pos[body, :2], (end_rot[body] @ start_rot[body].T)[:2, :2])
    return ends


def _draw_ends(
    ax: Axes,
    task: Task,
    outlines: list[list[np.ndarray]],
    starts: dict[str, np.ndarray],
    ends: dict[str, tuple[np.ndarray, np.ndarray]],
    colours: Sequence[tuple[float, ...]],
) -> None:
    """Objects that moved, dashed, where they ended."""
    for i, obj in enumerate(task.objects):
        if obj.name not in ends:
            continue
        at, turn = ends[obj.name]
        start = starts[obj.name]
        if np.linalg.norm(at - start) < MIN_ARROW and np.allclose(turn, np.eye(2), atol=0.02):
            continue
        for outline in outlines[i]:
            moved = (outline - start) @ turn.T + at
            ax.add_patch(
                Polygon(moved, closed=True, fill=False, edgecolor=colours[i][:3], linestyle="--", linewidth=1.4)
            )
            ax.update_datalim(moved)
        ax.annotate(
            f"{plot_text(obj.name)} (end)",
            _xy(at),
            xytext=(0, 0),
            textcoords="offset points",
            fontsize=7,
            ha="center",
            va="center",
            bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "alpha": 0.6, "linewidth": 0},
        )


LABEL_STEP = 6.0  # points: how far apart the places tried for a label are
LABEL_RINGS = 40


def _declutter(canvas: FigureCanvasAgg, ax: Axes) -> None:
    """Move each label (an annotation with text, placed in offset points) off the labels placed before it: to the
    nearest free place on rings of growing radius around where it was asked for. Each label is measured once and its
    places are tried all at once (shifted boxes against the placed ones): a program that makes hundreds of labels
    costs the host a fraction of a second, not a minute (measuring each try was quadratic in the labels)."""
    renderer = canvas.get_renderer()
    pixels = renderer.points_to_pixels(1.0)
    directions = [(0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (-1, 1), (1, -1), (-1, -1)]
    rings = [(2 * LABEL_STEP * r * dx, LABEL_STEP * r * dy) for r in range(1, LABEL_RINGS) for dx, dy in directions]
    tries = np.array([(0.0, 0.0), *rings])
    shifts = np.tile(tries * pixels, 2)  # (ntry, 4): each try's shift of a box's x0, y0, x1, y1
    placed = np.zeros((0, 4))
    for label in [t for t in ax.texts if isinstance(t, Annotation) and t.get_text()]:
        x0, y0 = label.xyann
        box = label.get_window_extent(renderer).padded(1.5)
        boxes = np.array([box.x0, box.y0, box.x1, box.y1]) + shifts
        overlaps = (
            (boxes[:, None, 0] < placed[None, :, 2])
            & (boxes[:, None, 2] > placed[None, :, 0])
            & (boxes[:, None, 1] < placed[None, :, 3])
            & (boxes[:, None, 3] > placed[None, :, 1])
        ).any(axis=1)
        free = np.flatnonzero(~overlaps)
        k = int(free[0]) if free.size else len(tries) - 1  # none free: the last place tried, as far out as it goes
        label.xyann = (x0 + tries[k, 0], y0 + tries[k, 1])
        placed = np.vstack([placed, boxes[k]])


def _xy(point: np.ndarray) -> tuple[float, float]:
    """An x-y point as matplotlib's annotations take it."""
    return float(point[0]), float(point[1])


def _start(task: Task, path_xy: np.ndarray | None) -> np.ndarray:
    if path_xy is not None:
        return path_xy[0]
    return np.asarray(robots.get(task.embodiment).pictures.start_xy(task), dtype=float)


def _draw_robot_box(ax: Axes, task: Task, at: np.ndarray, *, end: bool = False) -> None:
    """The robot where it started (filled), or where it ended (``end``: dashed)."""
    size = robots.get(task.embodiment).pictures.footprint(task)
    label = "robot end" if end else "robot start"
    if size is None:  # a robot drawn as a marker (a gripper)
        ax.plot(*at, marker="s", color=ROBOT, markersize=8, label=label, fillstyle="none" if end else "full")
        return
    corner = (at[0] - size[0] / 2, at[1] - size[1] / 2)
    if end:
        box = Rectangle(corner, size[0], size[1], fill=False, edgecolor=ROBOT, linestyle="--", linewidth=1.4)
    else:
        box = Rectangle(corner, size[0], size[1], facecolor=ROBOT, alpha=0.5, edgecolor="black", linewidth=0.8)
    box.set_label(label)
    ax.add_patch(box)


def _draw_calls(
    ax: Axes,
    task: Task,
    rollout: Rollout,
    start: np.ndarray,
    centres: dict[str, np.ndarray],
    path_times: np.ndarray | None,
    path_xy: np.ndarray | None,
) -> np.ndarray:
    """An arrow per motion skill call, from the robot (or the pushed object) to the call's target; ``centres``
    follow the objects moved by calls that ended ``done``. Returns where the robot ended (as the calls say)."""
    params = {s.name: [kind for _, kind in s.params] for s in robots.get(task.embodiment).skills if s.kind == "motion"}
    robot_at = start.copy()
    step = 0
    for call in rollout.calls:
        kinds = params.get(call.skill)
        if not kinds or "position" not in kinds:
            continue
        step += 1
        target = np.asarray(call.args[kinds.index("position")][:2], dtype=float)
        moves_object = "name" in kinds
        if moves_object:
            name = call.args[kinds.index("name")]
            origin = centres.get(name, robot_at)
        elif path_xy is not None and path_times is not None:  # a failed move: drawn from where the robot stopped
            origin = _position_at(path_times, path_xy, call.ended if call.outcome != "done" else call.started)
        else:
            origin = robot_at
        if call.outcome != "done" or np.linalg.norm(target - origin) >= MIN_ARROW:  # up-and-down moves: no arrow
            _arrow(ax, origin, target, call, PUSH if moves_object else ROBOT, step)
        if moves_object and call.outcome == "done":
            centres[name] = target
        if not moves_object:
            robot_at = target if call.outcome == "done" else robot_at
            if path_xy is not None and path_times is not None:
                robot_at = _position_at(path_times, path_xy, call.ended)
    return robot_at


def _arrow(ax: Axes, origin: np.ndarray, target: np.ndarray, call: SkillCall, colour: Colour, step: int) -> None:
    failed = call.outcome != "done"
    style = {"color": REFUSED if failed else colour, "linestyle": "--" if failed else "-", "linewidth": 1.6}
    ax.annotate("", xy=_xy(target), xytext=_xy(origin), arrowprops={"arrowstyle": "->", **style})
    ax.update_datalim([origin, target])  # arrows are annotations: make room for them
    mid = (origin + target) / 2
    ax.annotate(
        plot_text(f"{step}. {call.skill}"),
        _xy(mid),
        xytext=(0, 0),
        textcoords="offset points",
        fontsize=6.5,
        color=style["color"],
        ha="center",
        va="bottom",
    )
    if failed:  # the cross marks where it ended
        ax.plot(*origin, marker="x", color=REFUSED, markersize=9, mew=2)
        ax.annotate(
            plot_text(capped(f"{call.outcome}: {call.reason or ''}", REASON_CHARS)),
            _xy(origin),
            xytext=(4, -10),
            textcoords="offset points",
            fontsize=6.5,
            color=REFUSED,
        )


def write_plan(
    path: Path, task: Task, rollout: Rollout, *, scene: Scene | None = None, track: Track | None = None
) -> Path:
    """Write the plan of ``rollout`` as a PNG at ``path``."""
    fig = plan_figure(task, rollout, scene=scene, track=track)
    path.parent.mkdir(parents=True, exist_ok=True)
    with _without_glyph_warnings():
        fig.savefig(path)
    return path


@contextlib.contextmanager
def _without_glyph_warnings() -> Iterator[None]:
    """Matplotlib's warning that a label's character is missing from the font (a program may name an object in any
    script): the picture shows a box for it; the warning quoted the host's source path to the user."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"Glyph \d+ .*missing from font", category=UserWarning)
        yield
