"""Terrain following for the quadruped's moves: reading the feet's paths ahead, where a move must stop and why, and
the legs and the lift that carry the body over what the feet cross.

When a move starts, and again when the terrain under a foot changed or the stretch read runs out, downward rays
read the path of each of the four feet from just behind it to :data:`~robotool.robots.quadruped.terrain.LOOKAHEAD`
past the move's end (at most ``scan_ahead`` at a time), and :mod:`.terrain` checks every foot's path against the
legs' limits and against the friction of the geoms it crosses (a slope steeper than ``atan(friction)``, in that
world: the feet are frictionless in the simulation and the x-y servos would hold the body on any slope): a finding
moves the stopping point to just before it, and once the robot has stopped there the skill is refused with the
measured value, the limit and where. A cloth is no footing over a gap: the rays see through it
to what carries it; nor is a surface narrower than a foot (a blade on edge, a ridge): the foot comes down beside it
(:mod:`.footholds`). Every control tick, in all moving worlds at once, a few rays under and ahead of each foot tell
whether a foot is crossing an accepted edge: then the lift motor carries the body so that foot clears the higher
surface (a step up, a stridden gap), or lets it down slowly past a drop, and the x-y setpoint waits until the foot
is clear. Otherwise the lift is off and the robot's weight rests on its feet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import BELLY_HEIGHT, OFF
from robotool.robots.quadruped.footholds import Footholds, comes_down_to, side_points
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.terrain import (
    EDGE_KINDS,
    FOOT_NAMES,
    FOOT_RADIUS,
    LOOKAHEAD,
    RADIUS_SAMPLES,
    RISE,
    SLOPE_HALF,
    SPACING,
    Finding,
    TerrainKind,
    clamp,
    finding_kind,
    first_slip,
    first_where,
    limit_of,
    rotated,
    scan_paths,
    steepness,
    too_steep,
)


@dataclass
class TerrainState:
    """Per world (index first): the last reading of the feet's paths and what it says about the move in progress,
    and the legs' and the lift's setpoints."""

    rescan: np.ndarray  # (nworld,) bool: read the paths again at the next tick
    scan_t0: np.ndarray  # (nworld,) m of travel at the last reading: sample k lies at scan_t0 - back + k * SPACING
    heights: np.ndarray  # (nworld, 4, samples) m: the surface under each foot's path
    level: np.ndarray  # (nworld, 4, samples) m: the level each foot accepted along its path
    stop: np.ndarray  # (nworld,) m of travel along the move where the body must stop
    findings: list[Finding | None]  # why it must stop there (None: the move's end)
    halted: np.ndarray  # (nworld,) bool: the move was refused for want of footing
    hover_from: np.ndarray  # (nworld, 4) m of travel where each foot began to cross an edge (NaN: not crossing)
    lift: np.ndarray  # (nworld,) m: the lift's setpoint (NaN: off)
    legs: np.ndarray  # (nworld, 4) m: the legs' setpoints (negative: reaching down)

    @classmethod
    def empty(cls, nworld: int, samples: int, press: float) -> TerrainState:
        return cls(
            rescan=np.zeros(nworld, dtype=bool),
            scan_t0=np.zeros(nworld),
            heights=np.full((nworld, 4, samples), np.nan),
            level=np.full((nworld, 4, samples), np.nan),
            stop=np.zeros(nworld),
            findings=[None] * nworld,
            halted=np.zeros(nworld, dtype=bool),
            hover_from=np.full((nworld, 4), np.nan),
            lift=np.full(nworld, np.nan),
            legs=np.full((nworld, 4), -press),  # standing: each leg carries its share
        )


@dataclass
class Footing:
    """What :meth:`TerrainFollowing._footing` found on each foot's path (k, 4) of one scan: where a slope or a slippery
    surface starts (the scan's sample; ``samples``: none), the sample where it was read (a slope: the middle of its
    run), whether it is a slope (else a want of grip), its measured value and its limit, as a :class:`Finding`
    carries them, and what the foot would stand on (a want of grip: flat, foot by foot)."""

    start: np.ndarray
    read: np.ndarray
    slope: np.ndarray
    measured: np.ndarray
    limit: np.ndarray
    surface: list[str]

    def finding(self, k: int, foot: int, where: np.ndarray) -> Finding:
        """The finding of ``foot`` in the scan's ``k``-th world, met at ``where`` (x-y)."""
        return Finding(
            "slope" if self.slope[k, foot] else "grip",
            float(self.measured[k, foot]),
            float(self.limit[k, foot]),
            (float(where[0]), float(where[1])),
            FOOT_NAMES[foot],
            "" if self.slope[k, foot] else self.surface[4 * k + foot],
        )


@dataclass(frozen=True)
class ReadingPattern:
    """Where :class:`TerrainFollowing` reads, fixed by the config and the body's size."""

    offsets: np.ndarray  # (5,) m: the per-tick samples along a foot's path (``config.local``)
    torso_grid: np.ndarray  # (n, 2) m: the rays under the torso, in its frame
    along: np.ndarray  # (samples,) m of travel of each sample of a reading, from the foot
    hold_len: int  # samples a foot crossing down holds behind an edge
    span: np.ndarray  # the samples :meth:`TerrainFollowing.lift` reads around a foot's centre
    edge_kinds: np.ndarray  # the scan codes of :data:`~.terrain.EDGE_KINDS`

    @classmethod
    def of(cls, config: QuadrupedConfig, half: np.ndarray) -> ReadingPattern:
        hold_len = round(config.hold_behind / SPACING)
        return cls(
            offsets=config.local,
            torso_grid=np.array(config.torso_grid) * half,
            along=-config.back + np.arange(config.samples) * SPACING,
            hold_len=hold_len,
            span=np.arange(-hold_len - RADIUS_SAMPLES, round(config.lift_ahead / SPACING) + 1),
            edge_kinds=np.array(EDGE_KINDS),
        )


class TerrainFollowing:
    """Reads the terrain along each move and sets the legs and the lift (state: :class:`TerrainState`)."""

    def __init__(self, senses: Senses, rays: Rays, limits: QuadrupedLimits, config: QuadrupedConfig):
        self.senses, self.rays, self.limits, self.config = senses, rays, limits, config
        self.samples, self.behind = config.samples, config.behind
        self.state = TerrainState.empty(senses.sim.nworld, self.samples, config.press)
        self.layout = ReadingPattern.of(config, senses.facts.half)
        self.footholds = Footholds.of(senses.sim.scene.model)

    def start_move(self, w: int) -> None:
        """A new move in world ``w``: read its paths at the next tick."""
        s = self.state
        s.stop[w] = 0.0
        s.findings[w] = None
        s.rescan[w] = True
        s.level[w] = np.nan
        s.hover_from[w] = np.nan
        s.halted[w] = False

    def indices(self, worlds: np.ndarray, travel: np.ndarray) -> np.ndarray:
        """Sample indices (k, 5) of the ``config.local`` offsets ahead of the feet in each world's last reading."""
        t = travel - self.state.scan_t0[worlds] + self.config.back
        return np.round((t[:, None] + self.layout.offsets[None, :]) / SPACING).astype(int)

    def gather(self, table: np.ndarray, worlds: np.ndarray, index: np.ndarray) -> np.ndarray:
        """``table`` (nworld, 4, samples) of ``worlds`` (k,) at ``index`` (k, n) for every foot -> (k, 4, n) (NaN out
        of range)."""
        ok = (index >= 0) & (index < self.samples)
        return np.where(ok[:, None, :], self._take(table, worlds, index), np.nan)

    def _take(self, table: np.ndarray, worlds: np.ndarray, index: np.ndarray) -> np.ndarray:
        """``table`` (nworld, 4, samples) of ``worlds`` (k,) at ``index`` (k, n), clamped to the samples, for every
        foot -> (k, 4, n)."""
        rows = (worlds[:, None] * 4 + np.arange(4)[None, :]) * self.samples
        return np.take(table.reshape(-1), rows[:, :, None] + clamp(index, 0, self.samples - 1)[:, None, :])

    def local(
        self, worlds: np.ndarray, centres: np.ndarray, body: np.ndarray, u: np.ndarray, pushing: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Heights and objects (k, 4, 5) at the ``config.local`` offsets along each foot's path (direction ``u``
        (k, 2)), and the highest surface under the torso (k,) at ``body`` (k, 2) (the object ``pushing`` (k,) left
        out)."""
        layout = self.layout
        k, n = len(worlds), 4 * len(layout.offsets)
        xy = np.empty((k, n + len(layout.torso_grid), 2))
        xy[:, :n] = (centres[:, :, None, :2] + layout.offsets[None, None, :, None] * u[:, None, None, :]).reshape(
            k, n, 2
        )
        xy[:, n:] = body[:, None, :] + rotated(layout.torso_grid, self.senses.yaw(worlds))
        top = centres[:, :, 2].min(axis=1) + self.config.ray_height
        z, objects = self.rays.cast(worlds, xy, top)
        pushed = (objects == pushing[:, None]) & (objects >= 0)
        under_torso = np.where(pushed[:, n:], -np.inf, z[:, n:]).max(axis=1)
        return z[:, :n].reshape(k, 4, -1), objects[:, :n].reshape(k, 4, -1), under_torso

    def scan(
        self,
        worlds: np.ndarray,
        travel: np.ndarray,
        centres: np.ndarray,
        u: np.ndarray,
        length: np.ndarray,
        pushing: np.ndarray,
    ) -> None:
        """Read and check the feet's paths ahead in ``worlds`` (moves along ``u`` (k, 2) of ``length`` (k,), pushing
        object ``pushing`` (k,)); set where each must stop and why."""
        s, config, samples, behind = self.state, self.config, self.samples, self.behind
        bottom = centres[:, :, 2] - FOOT_RADIUS
        ahead = clamp(length - travel, 0.0, config.scan_ahead) + LOOKAHEAD
        along = self.layout.along
        sample = np.minimum(along, ahead[:, None])  # (k, samples)
        points = centres[:, :, None, :2] + sample[:, None, :, None] * u[:, None, None, :]
        read = samples  # the samples past every world's reach repeat its last: those are read once
        if np.isfinite(ahead).all():
            read = min(samples, int(np.count_nonzero(along < ahead.max())) + 1)
        xy, top = points[:, :, :read].reshape(len(worlds), -1, 2), bottom.min(axis=1) + config.ray_height
        read_back = self._on_footholds(worlds, xy, u, top, self.rays.surface(worlds, xy, top))
        z, solid, geoms, cloth = (
            np.concatenate([a, np.repeat(a[:, :, -1:], samples - read, axis=2)], axis=2)
            for a in (r.reshape(*points.shape[:2], read) for r in read_back)
        )
        objects = self.rays.objects_of(geoms)
        under = z[:, :, behind - RADIUS_SAMPLES : behind + RADIUS_SAMPLES + 1]
        actual = np.minimum(bottom + RISE, np.nanmax(under, axis=2))
        now = self.indices(worlds, travel)[:, 1]
        before = self.gather(s.level, worlds, now[:, None])[:, :, 0]
        over_gap = np.nan_to_num(before - actual, nan=0.0) > self.limits.max_step_up  # striding a gap: keep its level
        start = np.where(over_gap, before, actual)
        into_gap = np.zeros(over_gap.shape)
        for k, f in zip(*np.nonzero(over_gap), strict=True):  # how far into it, from the last reading
            w, i = worlds[k], int(now[k])
            low = s.heights[w, f, : i + 1] < s.level[w, f, : i + 1] - self.limits.max_step_up
            edge = np.flatnonzero(~low)
            into_gap[k, f] = (i - (edge[-1] if edge.size else -1)) * SPACING
        pushed = (objects == pushing[:, None, None]) & (objects >= 0)
        z = np.where(pushed, start[:, :, None], z)
        result = scan_paths(
            z[:, :, behind:].reshape(-1, samples - behind), start.reshape(-1), self.limits, into_gap.reshape(-1)
        )
        level = np.concatenate(
            [np.repeat(start[:, :, None], behind, axis=2), result.level.reshape(len(worlds), 4, -1)], axis=2
        )
        s.heights[worlds], s.level[worlds] = z, level
        s.scan_t0[worlds] = travel
        s.rescan[worlds] = False
        index = result.index.reshape(len(worlds), 4) + behind
        kind = result.kind.reshape(len(worlds), 4)
        measured = result.measured.reshape(len(worlds), 4)
        meets = travel[:, None] + np.take_along_axis(sample, np.minimum(index, samples - 1), axis=1)
        edges = (kind[:, :, None] == self.layout.edge_kinds).any(axis=2)  # a gap or a drop
        past = np.where(edges, FOOT_RADIUS, 0.0)  # a gap or a drop: the foot's centre passes its edge
        relevant = (kind != TerrainKind.NONE) & (meets - past <= length[:, None])
        margin = np.where(edges, FOOT_RADIUS + config.edge_margin, config.stop_margin)  # centre/edge, foot/face
        footing = self._footing(worlds, np.where(pushed, z, solid), geoms, self.rays.grip(geoms, cloth), points, behind)
        slope_meets = travel[:, None] + np.take_along_axis(sample, np.minimum(footing.start, samples - 1), axis=1)
        slope_meets = np.where((footing.read < index) & (slope_meets <= length[:, None]), slope_meets, np.inf)
        stop_at = np.minimum(  # before a slope or a slippery surface, or where it stands when already on one
            np.where(relevant, meets - margin, np.inf).min(axis=1),
            np.maximum(slope_meets - config.stop_margin, travel[:, None]).min(axis=1),
        )
        limit = np.where(length > travel + config.scan_ahead, travel + config.scan_ahead, length)
        halted = s.halted[worlds]
        s.stop[worlds] = np.where(halted, s.stop[worlds], np.minimum(limit, stop_at))
        for k, w in enumerate(worlds):
            hits = np.flatnonzero(relevant[k])
            if halted[k]:  # refused already: the move ends where it stopped
                continue
            foot = int(np.argmin(slope_meets[k]))
            if np.isfinite(slope_meets[k, foot]) and (not hits.size or slope_meets[k, foot] <= meets[k, hits].min()):
                s.findings[w] = footing.finding(k, foot, points[k, foot, footing.start[k, foot]])
                continue
            if not hits.size:
                s.findings[w] = None
                continue
            foot = int(hits[np.argmin(meets[k, hits])])
            where = points[k, foot, index[k, foot]]
            kind_name = finding_kind(int(kind[k, foot]))
            s.findings[w] = Finding(
                kind_name,
                round(float(measured[k, foot]), 3),
                limit_of(kind_name, self.limits),
                (float(where[0]), float(where[1])),
                FOOT_NAMES[foot],
            )

    def _on_footholds(
        self,
        worlds: np.ndarray,
        xy: np.ndarray,
        u: np.ndarray,
        top: np.ndarray,
        read: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``read``, what the rays from ``top`` (k,) over ``xy`` (k, n, 2) met (:meth:`~.rays.Rays.surface`: heights,
        solids, geoms, cloth links; (k, n) each), where the feet moving along ``u`` (k, 2) would stand: over a surface
        that may be narrower than a foot, rays beside it tell, and where it is, the foot comes down beside it, to what
        the rays there met (:mod:`.footholds`)."""
        narrow = self.footholds.narrow(self.senses.state, worlds, read[2])
        if not narrow.any():
            return read
        rows = np.flatnonzero(narrow.any(axis=1))
        count = narrow[rows].sum(axis=1)
        first = np.argsort(~narrow[rows], axis=1, kind="stable")[:, : count.max()]  # each row's narrow samples first
        pick = np.where(np.arange(first.shape[1])[None, :] < count[:, None], first, first[:, :1])  # padded
        sides = side_points(np.take_along_axis(xy[rows], pick[:, :, None], axis=1), u[rows][:, None, :])
        beside = self.rays.surface(worlds[rows], sides.reshape(len(rows), -1, 2), top[rows])
        which = comes_down_to(np.take_along_axis(read[0][rows], pick, axis=1), beside[0].reshape(*pick.shape, 4))
        out = tuple(a.copy() for a in read)
        for a, side in zip(out, beside, strict=True):
            side = np.take_along_axis(side.reshape(*pick.shape, 4), np.maximum(which, 0)[..., None], axis=2)[..., 0]
            a[rows[:, None], pick] = np.where(which >= 0, side, np.take_along_axis(a[rows], pick, axis=1))
        return out[0], out[1], out[2], out[3]

    def _footing(
        self, worlds: np.ndarray, z: np.ndarray, geoms: np.ndarray, grip: np.ndarray, points: np.ndarray, behind: int
    ) -> Footing:
        """Where each foot's path (k, 4) from under the foot on first meets a surface that cannot carry the move in
        its world: a slope steeper than its friction holds, or a surface whose friction is under the grip the feet
        need there (``config.walk_grip`` plus a slope's tangent: :func:`~.terrain.first_slip`), whichever comes first
        (a slope on a tie); the paths' heights (of the solids: a cloth lies on them, or hangs from them), hit geoms and
        points as :meth:`scan` reads them, and the geoms whose friction the feet meet there (``grip``: a cloth lying
        on a solid where it is more slippery, :meth:`~.rays.Rays.grip`; a geom's friction as the perturbation scales
        it). A slippery surface that is also too steep somewhere on the paths is a slope (the robot could not even
        stand on it), met where the foot meets that surface."""
        n, hit = geoms.shape[2] - behind, grip[:, :, behind:]
        friction = self.rays.friction(worlds, hit)
        tangent = steepness(z, geoms, points)[:, :, behind:]
        over, angle, holds = too_steep(tangent, friction)  # none hit: no slope read
        steep, slope, limit = first_where(over, angle, holds)  # as first_steep finds it
        slip, have, need = first_slip(tangent, np.where(hit >= 0, friction, np.inf), self.config.walk_grip, angle)
        is_slope = (steep < n) & (np.maximum(steep - SLOPE_HALF, 0) <= slip)
        found = Footing(
            start=np.where(is_slope, np.maximum(steep + behind - SLOPE_HALF, 0), slip + behind),
            read=np.where(is_slope, steep, slip) + behind,
            slope=is_slope,
            measured=np.where(is_slope, np.round(slope, 1), np.round(have, 4)),
            limit=np.where(is_slope, np.round(limit, 1), np.round(need, 3)),
            surface=["" for _ in range(4 * len(worlds))],
        )
        for k, f in zip(*np.nonzero(~is_slope & (slip < n)), strict=True):  # rare: the surfaces of the slips only
            geom = hit[k, f, slip[k, f]]
            steep_there = over[k] & (hit[k] == geom)  # that surface too steep for its friction somewhere ahead
            if steep_there.any():
                first = np.argmax(steep_there.any(axis=0))
                g = int(np.argmax(steep_there[:, first]))
                found.slope[k, f] = True
                found.measured[k, f], found.limit[k, f] = round(angle[k, g, first], 1), round(holds[k, g, first], 1)
            found.surface[4 * k + f] = self.rays.surface_name(int(geom))
        return found

    def lift(
        self,
        worlds: np.ndarray,
        q: np.ndarray,
        qd: np.ndarray,
        travel: np.ndarray,
        centres: np.ndarray,
        local: np.ndarray,
        under_torso: np.ndarray,
        index: np.ndarray,
    ) -> np.ndarray:
        """Set the legs and the lift (the body's coordinates ``q`` (k, 5) moving at ``qd``); return the worlds (k,)
        that must wait for a foot to clear an edge.

        Each leg reaches down to the surface under its foot, a little further (``press``) so that it carries its
        share, the body level over the highest one and its torso ``torso_clearance`` above what lies under it;
        legs change length at ``leg_speed``. A foot crosses up while the level accepted from just behind it to
        ``lift_ahead`` ahead stands higher than the surface under it (a step up ahead, a stridden gap under it):
        the lift raises the body until that foot is ``clearance`` above that level. It crosses down from when the
        surface under its centre drops below the level it stood at (it bears weight up to the edge) until
        ``hold_behind`` past it: the lift holds the body. While the lift carries the body the legs keep their
        length and the tilt motors hold it level; once no foot crosses, the lift lets the body down onto its legs
        at ``descent_speed`` and switches off once they stand as they should and carry it (all in
        :class:`~robotool.robots.quadruped.quadruped_config.QuadrupedConfig`).
        """
        s, config, samples, sim = self.state, self.config, self.samples, self.senses.sim
        ids, dt = self.senses.facts.ids, self.senses.scene.control_dt
        hold_len = self.layout.hold_len
        centre = hold_len + RADIUS_SAMPLES  # the foot's centre in the window
        window = index[:, 1, None] + self.layout.span[None, :]  # around each foot's centre
        known = (window >= 0) & (window < samples)
        read = self._take(s.level, worlds, window)
        standing = np.where(known[:, None, centre], read[:, :, centre], np.nan)  # the level accepted under each foot
        last = np.round((s.stop[worlds] - s.scan_t0[worlds] + config.back) / SPACING)  # the move's end (the foot's)
        values = np.where(np.isnan(read) | ~(known & (window <= last[:, None]))[:, None, :], -np.inf, read)
        ahead = values[:, :, hold_len:].max(axis=2)
        behind = values[:, :, : hold_len + RADIUS_SAMPLES + 1].max(axis=2)  # up to the foot's centre
        under = local[:, :, :3].max(axis=2)
        below = local[:, :, 1]  # under the foot's centre: it bears weight up to the edge
        bottom = centres[:, :, 2] - FOOT_RADIUS
        up = ahead - under > RISE
        hold = ~up & (behind - below > RISE)
        crossing = (up | hold).any(axis=1)
        footing = np.abs(below - standing) <= RISE  # a surface the foot could stand on lies under it
        crossing &= ~self._no_footing(worlds, travel, up | hold, footing, centres)
        up &= crossing[:, None]
        clear = under_torso - BELLY_HEIGHT + config.torso_clearance  # the lowest the feet's level may be there
        stance = clamp(under - np.maximum(under.max(axis=1), clear)[:, None] - config.press, -self.reach, 0.0)
        legs = s.legs[worlds]
        step = clamp(stance - legs, -config.leg_speed * dt, config.leg_speed * dt)
        legs = np.where(crossing[:, None], legs, legs + step)  # held while the lift carries the body
        s.legs[worlds] = legs
        sim.ctrl[worlds[:, None], ids.leg_actuator] = legs
        need = np.where(up, ahead + config.clearance, np.where(hold, behind, -np.inf)) - bottom
        wanted = np.where(crossing, np.maximum(q[:, 2] + need.max(axis=1), clear), np.nan)
        previous = np.minimum(s.lift[worlds], q[:, 2]) - config.descent_speed * dt  # NaN: was off
        target = np.where(np.isnan(wanted), previous, np.fmax(wanted, previous))
        settled = np.all(np.abs(legs - stance) < 1e-3, axis=1)  # the legs stand where they should
        target = np.where(~crossing & settled & (target < q[:, 2] - config.release), np.nan, target)  # on its legs
        s.lift[worlds] = target
        off = np.isnan(target)
        sim.ctrl[worlds, ids.actuator[2]] = np.where(off, OFF, target)
        angle, rate = q[:, 3:], qd[:, 3:]
        level = clamp(-angle * config.tilt_gain - rate * config.tilt_damping, -1.0, 1.0) * ~off[:, None]
        sim.ctrl[worlds[:, None], ids.actuator[3:]] = level
        return np.any(up & (bottom < ahead + config.clearance / 2), axis=1)

    def let_go(self, worlds: np.ndarray) -> None:
        """The lift and the tilt motors let go in ``worlds`` (what the feet stand on gave way: the body goes down
        with it)."""
        ids = self.senses.facts.ids
        self.state.lift[worlds] = np.nan
        self.senses.sim.ctrl[worlds, ids.actuator[2]] = OFF
        self.senses.sim.ctrl[worlds[:, None], ids.actuator[3:]] = 0.0

    @property
    def reach(self) -> float:
        """m a leg reaches down."""
        return self.senses.facts.reach

    def _no_footing(
        self, worlds: np.ndarray, travel: np.ndarray, crossing: np.ndarray, footing: np.ndarray, centres: np.ndarray
    ) -> np.ndarray:
        """Worlds (k,) where a foot has been carried further than any edge needs (``crossing``: (k, 4) the feet
        crossing now) since it last passed over footing (``footing``: (k, 4) the surface under the foot's centre
        is the level it stands at, such as the tread between two steps): it found no footing. The move stops
        there, refused, and the lift lets go: what the feet stand on then carries the robot, or not."""
        s = self.state
        start = s.hover_from[worlds]
        fresh = np.isnan(start) | footing
        start = np.where(crossing & fresh, travel[:, None], np.where(crossing, start, np.nan))
        s.hover_from[worlds] = start
        carried = np.where(crossing, travel[:, None] - start, 0.0)
        too_far = (carried > self.config.max_hover).any(axis=1) | s.halted[worlds]
        for k in np.flatnonzero(too_far & ~s.halted[worlds]):
            w, foot = int(worlds[k]), int(np.argmax(carried[k]))
            where = centres[k, foot, :2]
            s.findings[w] = Finding(
                "gap",
                round(float(carried[k, foot]), 3),
                self.limits.max_gap,
                (float(where[0]), float(where[1])),
                FOOT_NAMES[foot],
            )
            s.stop[w] = float(travel[k])
            s.hover_from[w] = np.nan
            s.halted[w] = True
        return too_far
