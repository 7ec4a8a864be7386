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

from robotool.sim.warp_runtime import Float, Floats, Floats2, Floats3, Int, launch_on_cpu

wp.set_module_options({"fuse_fp": False})  # no fused multiply-adds: each product and sum rounds as numpy's do


@dataclass(frozen=True)
class FollowRules:
    """What the follower compares against (m; each finding's limit already with its measurement tolerance) and the
    code it writes for each kind of finding."""

    rise: float  # a rise over this is a step up the foot climbs onto
    step_limit: float  # a climb (from the lowest level of the last ``run`` samples) over this is a step finding
    max_step_up: float  # a dip deeper than this below the recent top is a gap or a step down
    gap_limit: float  # a gap wider than this is a finding
    drop_limit: float  # a step down deeper than this is a finding
    spacing: float  # m between samples
    radius: float  # the foot's radius
    run: int  # samples over which a rise or fall counts as one edge
    codes: tuple[int, int, int]  # the codes of a step, a gap and a drop finding

    @functools.cached_property
    def values(self) -> np.ndarray:
        """The thresholds as the kernel reads them."""
        r = self
        return np.array([r.rise, r.step_limit, r.max_step_up, r.gap_limit, r.drop_limit, r.spacing, r.radius])


@wp.func
def _fmax(a: Float, b: Float) -> Float:
    """The greater of two values, a NaN ignored (``np.fmax``)."""
    if wp.isnan(a):
        return b
    if wp.isnan(b):
        return a
    return wp.max(a, b)


@wp.func
def _fmin(a: Float, b: Float) -> Float:
    """The lesser of two values, a NaN ignored (``np.fmin``; negation is exact)."""
    return -_fmax(-a, -b)


@wp.kernel
def _follow(
    paths: Floats2,
    rules: Floats,
    run: Int,
    step_code: Int,
    gap_code: Int,
    drop_code: Int,
    out: Floats3,
    finding: Floats2,
):
    """``paths`` (P, n + 2): each path's heights, then its start level and how far it starts inside a gap; ``out``
    (P, n, 4): each kind's edge met at each sample, then the level stood at; ``finding`` (P, 3): the first finding's
    sample, code and measured value."""
    p = wp.tid()
    n = paths.shape[1] - 2
    rise, step_limit, max_step_up = rules[0], rules[1], rules[2]
    gap_limit, drop_limit, spacing, radius = rules[3], rules[4], rules[5], rules[6]
    zero, two = Float(0.0), Float(2.0)
    start = paths[p, n]
    current = start
    skip = Int(0)
    changed = -run  # the last sample whose level differs from the one before it (or is NaN)
    if wp.isnan(start):
        changed = Int(-1)
    for k in range(n):
        h = paths[p, k]
        low = current
        high = current
        if changed > k - run:  # the last ``run`` levels differ (the start level before the first): read them
            for j in range(k - run, k):
                recent = start
                if j >= 0:
                    recent = out[p, j, 3]
                low = _fmin(low, recent)
                high = _fmax(high, recent)
        found = Int(0)
        value = Float(0.0)
        if skip > 0:  # striding over a gap
            skip = skip - Int(1)
        else:
            climbed = h - low
            too_high = climbed > step_limit  # a step, or a slope as steep as one
            if h - current > rise or too_high:
                if too_high:
                    found = step_code
                    value = climbed
                out[p, k, 0] = climbed
                current = h
            elif high - h > max_step_up:  # from the top of an edge or of a steep slope down
                current = high
                back = Int(-1)
                for j in range(k, n):
                    if paths[p, j] >= current - max_step_up:
                        back = Int(j - k)
                        break
                if back >= 0:  # the surface comes back: a gap
                    entered = Float(0.0)
                    if k == 0:
                        entered = paths[p, n + 1]
                    width = Float(back) * spacing + two * radius
                    if entered > zero:
                        width = width + entered - radius
                    out[p, k, 1] = width
                    if width > gap_limit:
                        found = gap_code
                        value = width
                    else:
                        stride = wp.max(width - two * radius - entered, zero) / spacing
                        skip = Int(wp.rint(stride)) - Int(1)
                else:  # it does not: a step down
                    depth = current - h
                    out[p, k, 2] = depth
                    if depth > drop_limit:
                        found = drop_code
                        value = depth
                    else:
                        current = h
            else:
                current = h
        if found != 0:
            finding[p, 0] = Float(k)
            finding[p, 1] = Float(found)
            finding[p, 2] = value
            return
        before = start
        if k > 0:
            before = out[p, k - 1, 3]
        if current != before:  # (true where either is NaN)
            changed = k
        out[p, k, 3] = current


def follow(
    heights: np.ndarray, start: np.ndarray, into_gap: np.ndarray, rules: FollowRules
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Follow paths (P, n) of foot-supported heights from levels ``start`` (P,), ``into_gap`` (P,) m already inside a
    gap: the level stood at over each sample (P, n; NaN from a finding on), the finding's sample (P,; n: none), its
    code (P,; 0: none), its measured value (P,) and each kind's edge met at each sample (P, n, 3)."""
    npath, n = np.shape(heights)
    paths = np.empty((npath, n + 2))
    paths[:, :n], paths[:, n], paths[:, n + 1] = heights, start, into_gap
    out = np.zeros((npath, n, 4))
    out[..., 3] = np.nan
    finding = np.zeros((npath, 3))
    finding[:, 0] = n
    if npath and n:
        launch_on_cpu(_follow, npath, paths, rules.values, rules.run, *rules.codes, out, finding)
    return out[..., 3], finding[:, 0].astype(np.int64), finding[:, 1].astype(np.int64), finding[:, 2], out[..., :3]
