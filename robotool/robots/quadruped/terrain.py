"""The quadruped's legs against the terrain: steps, gaps and drops along the path of every foot.

One module serves the simulator's checks (heights read by rays in each world), the planner's predictions and the
ground-truth key concepts (heights from the task's geometry), with one tolerance. A move of the body is checked
foot by foot: each of the four feet sweeps a straight path, sampled every :data:`SPACING` metres, and
:func:`scan_paths` follows the surface a foot stands on along its path, from the height it stands at now:

- a rise is a step up; over ``max_step_up`` it is a ``step`` finding (a surface that rises or falls that much
  within :data:`SLOPE_RUN` counts as a step or an edge, however gently each sample changes: a steep slope, such as
  a strip of cloth sagging into a gap, is no footing);
- a dip deeper than a climbable step is a gap when the surface comes back up within the path (which runs
  :data:`LOOKAHEAD` past the move's end, so a move that ends over a gap still sees its far side): wider than
  ``max_gap`` it is a ``gap`` finding, else the foot strides over it; a dip that does not come back is a step down,
  deeper than ``max_step_down`` a ``drop`` finding;
- anything else (a slope, a small change) is followed.

A slope is footing only as steep as the surface's friction holds (the feet slide down one steeper than
``atan(friction)``): :func:`steepness` reads it under every sample and :func:`first_steep` finds the first that is
too steep, a ``slope`` finding (the simulator's check; the planner's and the key concepts' heights carry no friction).
A move also needs grip: the feet push the body along, so the surface's friction must carry the body's horizontal
acceleration over g (``walk_grip`` in :class:`~.quadruped_config.QuadrupedConfig`) plus a slope's tangent;
:func:`first_slip` finds the first sample whose friction does not, a ``grip`` finding (the simulator's check too).

A finding carries its kind, the measured value, the limit, where it starts (x-y) and which foot met it.
:func:`check_walk` answers whether a walk keeps within the limits (the simulator's and the planner's question);
:func:`survey_walk` also measures the edges within them (the key concepts' question), and :func:`exceeds` is the one
rule that judges a measured value against its limit.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from enum import IntEnum
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits

if TYPE_CHECKING:
    from robotool.robots.quadruped.path_kernel import FollowRules


class TerrainKind(IntEnum):
    """What a foot's path meets, as :class:`PathScan` codes it (0: nothing)."""

    NONE = 0
    STEP = 1
    GAP = 2
    DROP = 3


EDGE_KINDS: tuple[TerrainKind, ...] = (TerrainKind.GAP, TerrainKind.DROP)
"""The kinds whose edge a foot's centre passes (a step is met face on); for ``np.isin`` over scan codes."""

EdgeKind = Literal["step", "gap", "drop"]
FindingKind = Literal[EdgeKind, "slope", "grip"]
KINDS: tuple[EdgeKind, ...] = ("step", "gap", "drop")  # in :class:`TerrainKind` order (its codes 1, 2, 3)
RISE = 0.015  # m: a change smaller than this is the same surface (noise, slopes between samples)
TOLERANCE = 0.01  # m: measurement slack allowed over a limit (sampling and pose noise)
SPACING = 0.01  # m between samples along a foot's path
LOOKAHEAD = 0.6  # m read past the end of a move, so that a gap's far side is seen
SLOPE_RUN = 0.15  # m: a surface that rises or falls more than a step within this run is an edge, not a slope
FOOT_RADIUS = 0.03  # m
RADIUS_SAMPLES = int(np.ceil(FOOT_RADIUS / SPACING))
FOOT_NAMES = ("rear-right", "rear-left", "front-right", "front-left")  # the order of :func:`foot_offsets`
SLOPE_BASE = 0.1  # m: the run a slope is read over along a foot's path (a difference centred on the sample)
SLOPE_HALF = round(SLOPE_BASE / 2 / SPACING)  # samples on each side of a slope's reading
SLOPE_TOLERANCE = 1.0  # deg a slope may exceed the steepest its friction holds (sampling and pose noise)
PLANE_AGREES = 0.02  # the most the four feet's plane may rise along a path (a tangent) unlike the path's own reading

Heights = Callable[[np.ndarray], np.ndarray]
"""Surface heights under x-y points (n, 2) -> (n,)."""


@dataclass(frozen=True)
class Finding:
    """A limit of the legs that a move breaks: what, the measured value, the limit, where and which foot."""

    kind: FindingKind
    measured: float  # m: the step height, gap width or drop depth; deg: a slope; grip: the surface's friction
    limit: float  # m; deg: the steepest slope the surface's friction holds; grip: the friction the feet need there
    where: tuple[float, float]  # x-y where the foot meets it
    foot: str
    surface: str = ""  # grip: what the foot would stand on (an object's name, or the ground)

    def describe(self) -> str:
        """The refusal reason, with the measured value, the limit and where."""
        if self.kind == "slope":
            what = f"slope of {self.measured:.1f} deg exceeds the {self.limit:.1f} deg its surface's friction holds"
        elif self.kind == "grip":
            what = (
                f"{self.surface} is too slippery to walk on: its friction of {self.measured:.4g} is under the "
                f"{self.limit:.3f} the feet need to grip (the walk's acceleration over g, plus a slope's tangent)"
            )
        else:
            name = {"step": "step up", "gap": "gap", "drop": "drop"}[self.kind]
            what = f"{name} of {self.measured:.2f} m exceeds the limit of {self.limit:.2f} m"
        return f"{what} (at [{self.where[0]:.2f}, {self.where[1]:.2f}], under the {self.foot} foot)"


@dataclass(frozen=True)
class PathScan:
    """What :func:`scan_paths` found on each of P paths of n samples."""

    level: np.ndarray  # (P, n) surface the foot stands at over each sample (a stridden gap keeps its near level)
    index: np.ndarray  # (P,) first sample of the first finding (n when none)
    kind: np.ndarray  # (P,) a :class:`TerrainKind` code (NONE: no finding)
    measured: np.ndarray  # (P,) the finding's measured value
    met: np.ndarray  # (P, n, 3) each kind's edge (KINDS order) met at each sample, within its limit or not (0: none)


def finding_kind(code: int) -> EdgeKind:
    """The finding a :class:`PathScan` code (not :attr:`TerrainKind.NONE`) stands for."""
    return KINDS[TerrainKind(code) - TerrainKind.STEP]


def limit_of(kind: EdgeKind, limits: QuadrupedLimits) -> float:
    """The limit a finding of ``kind`` is checked against."""
    return {"step": limits.max_step_up, "gap": limits.max_gap, "drop": limits.max_step_down}[kind]


def exceeds(kind: EdgeKind, measured: float | np.ndarray, limits: QuadrupedLimits) -> Any:
    """Whether a measured step height, gap width or drop depth is beyond the legs' limit (allowing
    :data:`TOLERANCE`); element-wise for arrays."""
    return measured > limit_of(kind, limits) + TOLERANCE


def clamp(values: Any, lo: Any, hi: Any) -> Any:
    """``np.clip(values, lo, hi)``, element-wise, without its per-call checks (the controller calls it every tick)."""
    return np.minimum(np.maximum(values, lo), hi)


def foot_support(heights: np.ndarray) -> np.ndarray:
    """What a round foot rests on along paths (P, n): the highest surface within its radius of each sample.

    A slit narrower than the foot carries it; a gap reads :data:`FOOT_RADIUS` narrower on each side.
    """
    padded = np.pad(heights, ((0, 0), (RADIUS_SAMPLES, RADIUS_SAMPLES)), mode="edge")
    n = heights.shape[1]
    support = padded[:, :n].copy()
    for k in range(1, 2 * RADIUS_SAMPLES + 1):  # the window's samples one shift at a time (a NaN carries, as in max)
        np.maximum(support, padded[:, k : k + n], out=support)
    return support


def scan_paths(
    heights: np.ndarray, start: np.ndarray, limits: QuadrupedLimits, into_gap: np.ndarray | None = None
) -> PathScan:
    """Follow P foot paths (P, n) of surface heights from the levels ``start`` (P,) (module docstring).

    The heights are first taken as the foot rests on them (:func:`foot_support`); a gap's width is measured
    between the edges the foot's centre passes, plus the foot's diameter: the width between the surfaces.
    ``into_gap`` (P,) is how far a path starts inside a gap it is already striding (counted in its width).
    Each path is followed sample by sample in compiled code (:mod:`.path_kernel`): at every sample the surface is
    compared with the level the foot stands at and with the lowest and highest levels over the last
    :data:`SLOPE_RUN`; a path ends at its first finding (its level NaN from there).
    """
    from robotool.robots.quadruped.path_kernel import follow  # Warp loads on the first scan, not on every import

    supported = foot_support(np.asarray(heights, dtype=float))
    npath = supported.shape[0]
    already = np.zeros(npath) if into_gap is None else np.asarray(into_gap, dtype=float)
    level, index, kind, measured, met = follow(supported, np.asarray(start, dtype=float), already, _rules(limits))
    return PathScan(level=level, index=index, kind=kind, measured=measured, met=met)


@functools.lru_cache(maxsize=64)
def _rules(limits: QuadrupedLimits) -> FollowRules:
    """The follower's thresholds for ``limits`` (each finding's limit with :data:`TOLERANCE`, as :func:`exceeds`)."""
    from robotool.robots.quadruped.path_kernel import FollowRules

    return FollowRules(
        rise=RISE,
        step_limit=limit_of("step", limits) + TOLERANCE,
        max_step_up=limits.max_step_up,
        gap_limit=limit_of("gap", limits) + TOLERANCE,
        drop_limit=limit_of("drop", limits) + TOLERANCE,
        spacing=SPACING,
        radius=FOOT_RADIUS,
        run=round(SLOPE_RUN / SPACING),
        codes=(TerrainKind.STEP, TerrainKind.GAP, TerrainKind.DROP),
    )


def steepness(heights: np.ndarray, geoms: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The tangent of the surface's slope (k, 4, n) under the samples ``points`` (k, 4, n, 2) of the four feet's
    straight paths (their first two samples apart), read by rays: heights and hit geoms (k, 4, n). NaN: none read.

    Along each path it is the heights' difference over :data:`SLOPE_BASE` centred on the sample, where that run
    lies on one geom with no edge in it (no change over :data:`RISE` between samples); where the four feet read
    slopes on one geom and their heights lie on a plane (within ``RISE / 2``) that rises along each path as the
    path reads it, that plane's steepest slope (a slope across the path counts too).
    """
    n = heights.shape[2]
    half = SLOPE_HALF
    along = np.full(heights.shape, np.nan)
    if n <= 2 * half:
        return along
    runs = np.lib.stride_tricks.sliding_window_view(geoms, 2 * half + 1, axis=2)
    steps = np.lib.stride_tricks.sliding_window_view(np.abs(np.diff(heights, axis=2)), 2 * half, axis=2)
    read = (runs == runs[..., half : half + 1]).all(axis=3) & (steps.max(axis=3) <= RISE)
    rise = (heights[:, :, 2 * half :] - heights[:, :, : n - 2 * half]) / (2 * half * SPACING)
    along[:, :, half : n - half] = np.where(read, rise, np.nan)
    feet = points[:, :, 0]
    u = points[:, 0, 1] - points[:, 0, 0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    centred = feet - feet.mean(axis=1, keepdims=True)
    dz = heights - heights.mean(axis=1, keepdims=True)
    gradient = np.linalg.pinv(centred) @ dz  # (k, 2, n): the plane through the four feet's heights at each sample
    planar = (
        (np.abs(dz - centred @ gradient).max(axis=1) <= RISE / 2)
        & (np.abs(np.einsum("kd,kdn->kn", u, gradient)[:, None, :] - along) <= PLANE_AGREES).all(axis=1)
        & (geoms == geoms[:, :1]).all(axis=1)
    )
    return np.where(planar[:, None, :], np.linalg.norm(gradient, axis=1)[:, None, :], np.abs(along))


def too_steep(tangent: np.ndarray, friction: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where slopes (tangents, NaN: none) on surfaces of sliding ``friction`` are steeper than it holds
    (``atan(friction)`` and :data:`SLOPE_TOLERANCE`), the slopes and the steepest their friction holds (deg)."""
    angle, holds = np.degrees(np.arctan(tangent)), np.degrees(np.arctan(friction))
    return np.nan_to_num(angle, nan=-np.inf) > holds + SLOPE_TOLERANCE, angle, holds


def first_steep(tangent: np.ndarray, friction: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Along paths (..., n) of slopes (tangents, NaN: none) on surfaces of sliding ``friction``: the first sample
    steeper than its friction holds (:func:`too_steep`; n where none), that slope and the steepest its friction holds
    there (deg)."""
    over, angle, holds = too_steep(tangent, friction)
    index, slope, limit = first_where(over, angle, holds)
    return index, slope, limit


def first_slip(
    tangent: np.ndarray, friction: np.ndarray, grip: float, angle: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Along paths (..., n) of slopes (tangents, NaN: none) on surfaces of sliding ``friction`` (inf: none read): the
    first sample whose friction is under what the feet need to grip there (n where none), that friction and that need;
    ``angle``: the slopes in degrees where :func:`too_steep` has read them already.

    The feet need ``grip`` (the body's horizontal acceleration over g) plus the slope's tangent, the slope read less
    :data:`SLOPE_TOLERANCE` as :func:`first_steep` allows it (its sampling and pose noise)."""
    angle = np.degrees(np.arctan(tangent)) if angle is None else angle
    slope = np.maximum(np.nan_to_num(angle, nan=0.0) - SLOPE_TOLERANCE, 0.0)
    need = grip + np.tan(np.radians(slope))
    index, have, limit = first_where(friction < need, friction, need)
    return index, have, limit


def first_where(hit: np.ndarray, *values: np.ndarray) -> tuple[np.ndarray, ...]:
    """The first sample along paths (..., n) where ``hit`` (n where none) and each of ``values`` there."""
    n = hit.shape[-1]
    index = np.where(hit.any(axis=-1), hit.argmax(axis=-1), n)
    at = np.minimum(index, n - 1)[..., None]
    return (index, *(np.take_along_axis(v, at, -1)[..., 0] for v in values))


def foot_offsets(limits: QuadrupedLimits) -> np.ndarray:
    """x-y offsets (4, 2) of the feet's centres from the body's centre, level and unrotated (order FOOT_NAMES)."""
    hx, hy = limits.body_size[0] / 2 - FOOT_RADIUS, limits.body_size[1] / 2 - FOOT_RADIUS
    return np.array([[sx * hx, sy * hy] for sx in (-1, 1) for sy in (-1, 1)])


def turned(limits: QuadrupedLimits, quarters: int) -> QuadrupedLimits:
    """``limits`` as the body lies after ``quarters`` quarter turns about z: its x and y sizes swapped when odd (the
    terrain checks read the body's outline axis-aligned)."""
    if quarters % 2 == 0:
        return limits
    sx, sy, sz = limits.body_size
    return limits.model_copy(update={"body_size": (sy, sx, sz)})


def turned_feet(limits: QuadrupedLimits, quarters: int) -> np.ndarray:
    """Which foot (order FOOT_NAMES) stands at each of :func:`foot_offsets` ``(turned(limits, quarters))`` once the
    body has made ``quarters`` quarter turns."""
    moved = rotated(foot_offsets(limits), np.array([quarters * np.pi / 2]))[0]
    corners = foot_offsets(turned(limits, quarters))
    return np.argmin(np.linalg.norm(moved[None, :, :] - corners[:, None, :], axis=2), axis=1)


def quarter_turns(yaw: np.ndarray | float) -> np.ndarray:
    """The nearest whole number of quarter turns (0-3) to each heading ``yaw`` (rad)."""
    return np.mod(np.round(np.asarray(yaw) / (np.pi / 2)), 4).astype(int)


def rotated(points: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """x-y ``points`` (n, 2), or (k, n, 2) one set per heading, turned by each heading ``yaw`` (k,) rad -> (k, n, 2)."""
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x, y = points[..., 0], points[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


TURN_SAMPLE = 0.05  # rad between the headings, and m between the points of the outline, where a turn is read


def turn_sweep(limits: QuadrupedLimits, yaw: float, target: float, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """What a turn in place from heading ``yaw`` to ``target`` (rad) passes over, as offsets from the body's centre:
    the feet's arcs (n, 4, 2) and points covering its outline grown by ``margin`` (n, m, 2), at n headings."""
    angles = np.linspace(yaw, target, int(np.ceil(abs(target - yaw) / TURN_SAMPLE)) + 1)
    half = np.asarray(limits.body_size[:2]) / 2 + margin
    axes = (np.linspace(-h, h, int(np.ceil(2 * h / TURN_SAMPLE)) + 1) for h in half)
    outline = np.stack(np.meshgrid(*axes), axis=-1).reshape(-1, 2)
    return rotated(foot_offsets(limits), angles), rotated(outline, angles)


def foot_paths(feet: np.ndarray, direction: np.ndarray, length: float, back: float = 0.0) -> np.ndarray:
    """Sample points (4, n, 2) on the feet's straight paths: from ``back`` behind each foot ``feet`` (4, 2) to
    ``length`` ahead along the unit ``direction``."""
    t = np.arange(-back, length + SPACING / 2, SPACING)
    return feet[:, None, :] + t[None, :, None] * np.asarray(direction)[None, None, :]


def first_finding(scan: PathScan, points: np.ndarray, limits: QuadrupedLimits) -> tuple[Finding, int] | None:
    """The earliest finding over the feet of one move (scan of 4 paths, their points (4, n, 2)) and its sample."""
    hits = np.flatnonzero(scan.kind != TerrainKind.NONE)
    if not hits.size:
        return None
    foot = int(hits[np.argmin(scan.index[hits])])
    k = int(scan.index[foot])
    kind = finding_kind(int(scan.kind[foot]))
    where = points[foot, k]
    finding = Finding(
        kind,
        round(float(scan.measured[foot]), 3),
        limit_of(kind, limits),
        (float(where[0]), float(where[1])),
        FOOT_NAMES[foot],
    )
    return finding, k


def check_walk(
    heights: Heights,
    start: np.ndarray,
    waypoints: Iterable[np.ndarray],
    limits: QuadrupedLimits,
    start_levels: np.ndarray | None = None,
) -> Finding | None:
    """The first finding on an axis-aligned body's walk from ``start`` through ``waypoints`` (x-y), or None.

    Heights come from ``heights``; the feet start at ``start_levels`` (4,) (default: the surface under each foot,
    no higher than ``RISE`` above them). Each segment's feet carry their levels over from the last; the last segment
    reads :data:`LOOKAHEAD` past its end.
    """
    offsets = foot_offsets(limits)
    here = np.asarray(start, dtype=float)
    goals = [np.asarray(g, dtype=float) for g in waypoints]
    under = heights(here + offsets)
    levels = under if start_levels is None else np.minimum(np.asarray(start_levels) + RISE, under)
    for i, goal in enumerate(goals):
        delta = goal - here
        length = float(np.linalg.norm(delta))
        if length < 1e-6:
            continue
        u = delta / length
        ahead = length + (LOOKAHEAD if i == len(goals) - 1 else 0.0)
        points = foot_paths(here + offsets, u, ahead)
        h = heights(points.reshape(-1, 2)).reshape(4, -1)
        scan = scan_paths(h, levels, limits)
        found = first_finding(scan, points, limits)
        stop = round(length / SPACING)
        if found is not None and found[1] <= _reach(found[0].kind, stop):
            return found[0]
        levels = scan.level[:, min(stop, scan.level.shape[1] - 1)]
        here = goal
    return None


def _reach(kind: FindingKind, stop: int) -> int:
    """The last sample of a move ending at sample ``stop`` where an edge of ``kind`` counts: a foot meets a step
    at its face, and a gap or a drop once its centre passes the edge (a foot's radius after it is seen)."""
    return stop + (RADIUS_SAMPLES if kind != "step" else 0)


@dataclass(frozen=True)
class WalkSurvey:
    """What the four feet meet on a straight walk: the largest edge of each kind and the first that is too much."""

    largest: dict[EdgeKind, float]  # m: the highest step, widest gap and deepest drop met (0 where none)
    finding: Finding | None  # the first edge beyond its limit, or None


def survey_walk(heights: Heights, start: np.ndarray, goal: np.ndarray, limits: QuadrupedLimits) -> WalkSurvey:
    """Every step, gap and drop the feet of an axis-aligned body meet walking straight from ``start`` to ``goal``
    (x-y) over the surfaces ``heights``, read as :func:`check_walk` reads them (from the surface under each foot,
    :data:`LOOKAHEAD` past the end so that a gap's far side is seen), within their limits or not."""
    here, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    offsets = foot_offsets(limits)
    delta = goal - here
    length = float(np.linalg.norm(delta))
    largest: dict[EdgeKind, float] = dict.fromkeys(KINDS, 0.0)
    if length < 1e-6:
        return WalkSurvey(largest, None)
    points = foot_paths(here + offsets, delta / length, length + LOOKAHEAD)
    scan = scan_paths(heights(points.reshape(-1, 2)).reshape(4, -1), heights(here + offsets), limits)
    stop = round(length / SPACING)
    for i, kind in enumerate(KINDS):
        largest[kind] = float(scan.met[:, : _reach(kind, stop) + 1, i].max())
    found = first_finding(scan, points, limits)
    return WalkSurvey(largest, found[0] if found is not None and found[1] <= _reach(found[0].kind, stop) else None)
