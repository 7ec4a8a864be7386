"""The foot-path follower behind :func:`~robotool.robots.quadruped.terrain.scan_paths`, compiled: a Warp kernel on
the CPU, one thread per path, each following its samples in order.

The rules are sequential along a path (each sample is read against the level that the samples before it set), so
array code pays a round of calls per sample; compiled, four paths of 150 samples take about 0.1 ms instead of 2 ms
in numpy. Each path is followed alone (nothing in one path's answer depends on the others in the launch), and
halves round to even (``rint``), as numpy rounds them. Warp loads the first time a path is followed.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import warp as wp

from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import (
    FOOT_RADIUS,
    RISE,
    SLOPE_RUN,
    SPACING,
    TOLERANCE,
    TerrainKind,
    limit_of,
)
from robotool.sim.warp_runtime import cpu_view, init_warp


@dataclass(frozen=True)
class FollowRules:
    """What the follower compares against (m; each finding's limit with :data:`~.terrain.TOLERANCE`, as
    :func:`~.terrain.exceeds` reads it)."""

    rise: float  # a rise over this is a step up the foot climbs onto
    step_limit: float  # a climb (from the lowest level of the last ``run`` samples) over this is a step finding
    max_step_up: float  # a dip deeper than this below the recent top is a gap or a step down
    gap_limit: float  # a gap wider than this is a finding
    drop_limit: float  # a step down deeper than this is a finding
    spacing: float  # m between samples
    radius: float  # the foot's radius
    run: int  # samples over which a rise or fall counts as one edge

    @classmethod
    @functools.lru_cache(maxsize=64)
    def of(cls, limits: QuadrupedLimits) -> FollowRules:
        """The rules for ``limits``."""
        return cls(
            rise=RISE,
            step_limit=limit_of("step", limits) + TOLERANCE,
            max_step_up=limits.max_step_up,
            gap_limit=limit_of("gap", limits) + TOLERANCE,
            drop_limit=limit_of("drop", limits) + TOLERANCE,
            spacing=SPACING,
            radius=FOOT_RADIUS,
            run=round(SLOPE_RUN / SPACING),
        )

    @functools.cached_property
    def values(self) -> np.ndarray:
        """The thresholds as the kernel reads them (``run`` aside)."""
        r = self
        return np.array([r.rise, r.step_limit, r.max_step_up, r.gap_limit, r.drop_limit, r.spacing, r.radius])


wp.set_module_options({"fuse_fp": False})  # no fused multiply-adds: each product and sum rounds as numpy's do
STEP_CODE, GAP_CODE, DROP_CODE = (
    wp.constant(int(kind)) for kind in (TerrainKind.STEP, TerrainKind.GAP, TerrainKind.DROP)
)


@wp.func
def _fmin(a: wp.float64, b: wp.float64) -> wp.float64:
    """The lesser of two values, a NaN ignored (``np.fmin``)."""
    if wp.isnan(a):
        return b
    if wp.isnan(b):
        return a
    return wp.min(a, b)


@wp.func
def _fmax(a: wp.float64, b: wp.float64) -> wp.float64:
    """The greater of two values, a NaN ignored (``np.fmax``)."""
    if wp.isnan(a):
        return b
    if wp.isnan(b):
        return a
    return wp.max(a, b)


@wp.kernel
def _follow(
    paths: wp.array2d(dtype=wp.float64),
    rules: wp.array(dtype=wp.float64),
    run: wp.int32,
    out: wp.array3d(dtype=wp.float64),
    finding: wp.array2d(dtype=wp.float64),
):
    """``paths`` (P, n + 2): each path's heights, then its start level and how far it starts inside a gap; ``out``
    (P, n, 4): each kind's edge met at each sample, then the level stood at; ``finding`` (P, 3): the first finding's
    sample, code and measured value."""
    p = wp.tid()
    n = paths.shape[1] - 2
    rise, step_limit, max_step_up = rules[0], rules[1], rules[2]
    gap_limit, drop_limit, spacing, radius = rules[3], rules[4], rules[5], rules[6]
    start = paths[p, n]
    current = start
    skip = wp.int32(0)
    for k in range(n):
        h = paths[p, k]
        low = current
        high = current
        for j in range(k - run, k):  # the levels over the last ``run`` samples (the start level before the first)
            recent = start
            if j >= 0:
                recent = out[p, j, 3]
            low = _fmin(low, recent)
            high = _fmax(high, recent)
        found = wp.int32(0)
        value = wp.float64(0.0)
        if skip > 0:  # striding over a gap
            skip -= 1
        else:
            climbed = h - low
            too_high = climbed > step_limit  # a step, or a slope as steep as one
            if h - current > rise or too_high:
                if too_high:
                    found = STEP_CODE
                    value = climbed
                out[p, k, 0] = climbed
                current = h
            elif high - h > max_step_up:  # from the top of an edge or of a steep slope down
                current = high
                back = wp.int32(-1)
                for j in range(k, n):
                    if back < 0 and paths[p, j] >= current - max_step_up:
                        back = j - k
                if back >= 0:  # the surface comes back: a gap
                    entered = wp.float64(0.0)
                    if k == 0:
                        entered = paths[p, n + 1]
                    width = wp.float64(back) * spacing + wp.float64(2.0) * radius
                    if entered > wp.float64(0.0):
                        width = width + entered - radius
                    out[p, k, 1] = width
                    if width > gap_limit:
                        found = GAP_CODE
                        value = width
                    else:
                        stride = wp.max(width - wp.float64(2.0) * radius - entered, wp.float64(0.0)) / spacing
                        skip = wp.int32(wp.rint(stride)) - 1
                else:  # it does not: a step down
                    depth = current - h
                    out[p, k, 2] = depth
                    if depth > drop_limit:
                        found = DROP_CODE
                        value = depth
                    else:
                        current = h
            else:
                current = h
        if found != 0:
            finding[p, 0] = wp.float64(k)
            finding[p, 1] = wp.float64(found)
            finding[p, 2] = value
            return
        out[p, k, 3] = current


def follow(
    heights: np.ndarray, start: np.ndarray, into_gap: np.ndarray, limits: QuadrupedLimits
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Follow paths (P, n) of foot-supported heights from levels ``start`` (P,), ``into_gap`` (P,) m already inside a
    gap: the level stood at over each sample (P, n; NaN from a finding on), the finding's sample (P,; n: none), its
    code (P,; 0: none), its measured value (P,) and each kind's edge met at each sample (P, n, 3)."""
    rules = FollowRules.of(limits)
    npath, n = np.shape(heights)
    paths = np.empty((npath, n + 2))
    paths[:, :n], paths[:, n], paths[:, n + 1] = heights, start, into_gap
    out = np.zeros((npath, n, 4))
    out[..., 3] = np.nan
    finding = np.zeros((npath, 3))
    finding[:, 0] = n
    if npath and n:
        init_warp()
        wp.launch(
            _follow,
            dim=npath,
            inputs=[cpu_view(paths), cpu_view(rules.values), rules.run, cpu_view(out), cpu_view(finding)],
            device="cpu",
        )
    return out[..., 3], finding[:, 0].astype(np.int64), finding[:, 1].astype(np.int64), finding[:, 2], out[..., :3]
