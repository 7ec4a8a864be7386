"""What the stride of a walk or a climb moves, for the quadruped's referee: an object the stride carries back under the
feet is moved as a push moves it, so it and what goes along with it are weighed against the push limit, whether or not
it rams anything (:class:`StrideLoads`; found by adversarial runs: walking off a 15 kg cart on free rollers, or off a
1 kg board lying on it, kicked the cart back until it rolled off its rear roller onto the floor; a slick board kicked
back 2.5 cm coasted on with the cart; a board walked along rolled a 20 kg drum out from under it off a ledge)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import known_lengths

TURN = np.radians(6.0)
"""rad an object may turn about the vertical since a ride began before its sweep counts as travel (a lever's board
yaws a degree or two as it tips under the feet; a plank swung into line turns tens of degrees)."""
SLIP = 0.3  # the most an object may shift against a driven one, as a share of the driven one's own travel, and go
# along with it: the cart under a driven board shifts about 1 % of it; a roller rolling under it stays half behind

Group = Callable[[np.ndarray, np.ndarray], np.ndarray]  # (worlds, index) -> (k, nobject) what touches each object


class Rides(Protocol):
    """The referee's per-world state that :class:`StrideLoads` reads and keeps."""

    drift: np.ndarray  # (nworld, nobject) m each object travelled across under the feet since it rested
    ride_start: np.ndarray  # (nworld, nobject, 3) where each object was when the stride first moved anything since it
    # was last pushed (NaN: not yet)
    ride_top: np.ndarray  # (nworld, nobject) m the highest each object has been since then (NaN: not yet)
    ride_frames: np.ndarray  # (nworld, nobject, 4) each object's orientation then (a unit quaternion)
    ride_touched: np.ndarray  # (nworld, nobject) bool: touched what the stride carried (or was carried), in a ride
    ride_carried: np.ndarray  # (nworld, nobject) bool: carried by the stride in a ride


class StrideLoads:
    """Weighs what the stride moves (its state lives in the referee's: :class:`Rides`)."""

    def __init__(self, senses: Senses, limits: QuadrupedLimits, config: QuadrupedConfig):
        self.senses, self.limits, self.config = senses, limits, config

    def weigh(
        self, rides: Rides, mask: np.ndarray, centres: np.ndarray, resting: np.ndarray, group: Group
    ) -> dict[int, tuple[str, float]]:
        """Find the worlds in ``mask`` where the stride moves more than the push limit. A ride goes on while the stride
        carries an object across under the feet (``rides.drift``) or what touched what it carried still moves
        (``resting``, (nworld, nobject)); what the rides move counts from where it was when the stride first moved
        anything, over every ride since, until the robot pushes it itself (a fourth adversarial run: a board held to
        under 3 cm of travel, kicked again and again, knocked a 20 kg drum 0.7 m along in strokes of under 3 cm). An
        object the stride carried that lies more than ``shove`` across from there (its centre's travel and the arc its
        corners swept about the vertical, :meth:`_swept`: four quarter turns in place on a 20 kg plank on a post swung
        it into line over a gap while its centre moved 2-5 mm, found by an adversarial run; what touched it is read the
        same way) is moved by the robot, as by a push, whether it moved under the feet or coasted on after them (a board
        kicked back 2.5 cm coasted 0.85 m on with the 15 kg cart under it); so are the movable objects that touched what
        it carried, directly or through others (``group``), that lie more than ``shove`` across from there and have
        shifted against it by no more than :data:`SLIP` of its travel (what it rides on and rolls with it, what rides on
        it; not a roller it rolls on), or went on more than ``shove`` farther than it (knocked on by it: the drum), or
        sank more than ``shove``, however little it moved itself (a board walked along rolled a 20 kg drum out from
        under it off a ledge; a board kicked 1.5 cm between stops knocked one off a ledge). What rose more than
        ``shove`` is a lever's load, the lever's work, as long as it does not sink back below where it was by more than
        that (a 10 kg cube a lever lifted rode 12-19 cm back on the board walked along, off a shelf, and came down).
        Returns, for each world where they weigh more than the push limit, the reason, naming the carried object, and
        their mass."""
        shove, limit, drift = self.config.shove, self.limits.max_push_mass, rides.drift
        start, top, touched, carried = rides.ride_start, rides.ride_top, rides.ride_touched, rides.ride_carried
        carrying = (drift > 0) & mask[:, None]
        riding = mask & (carrying.any(axis=1) | (touched & ~resting).any(axis=1))
        if not riding.any():  # (most ticks) nothing carried, nothing moved
            return {}
        begun = riding[:, None] & np.isnan(start[:, :, 0])
        start[begun] = centres[begun]
        rides.ride_frames[begun] = self.senses.frames()[begun]
        top[riding] = np.fmax(top[riding], centres[riding, :, 2])
        carried |= carrying
        touched |= carrying
        if carrying.any():
            np.logical_or.at(touched, np.nonzero(carrying)[0], group(*np.nonzero(carrying)))
        travel = centres - start  # (nworld, nobject, 3) NaN where no ride
        across = known_lengths(np.linalg.norm(travel[:, :, :2], axis=2))
        worlds, objects = np.nonzero(carried & riding[:, None])
        if worlds.size == 0:
            return {}
        rows = np.arange(len(worlds))
        moved = across[worlds] + self._swept(worlds, objects, touched[worlds], rides.ride_frames)  # (k, nobject)
        slip = np.linalg.norm(travel[worlds, :, :2] - travel[worlds, objects][:, None, :2], axis=2)
        lifted = top[worlds] - start[worlds, :, 2] > shove
        sank = start[worlds, :, 2] - centres[worlds, :, 2] > shove
        knocked = moved > moved[rows, objects][:, None] + shove  # farther than what drove it: knocked on
        along = touched[worlds] & (moved > shove) & (~lifted | sank)
        along &= (slip <= SLIP * moved[rows, objects][:, None]) | sank | knocked
        along[rows, objects] = moved[rows, objects] > shove
        load = (self.senses.masses(worlds) * along).sum(axis=1)
        names = self.senses.scene.object_names
        found: dict[int, tuple[str, float]] = {}
        for k in np.flatnonzero(load > limit).tolist():
            moved = sorted(np.flatnonzero(along[k]).tolist(), key=lambda o: o != objects[k])  # the carried one first
            what = ", ".join(names[o] for o in moved)
            reason = (
                f"{names[objects[k]]}, driven by the stride of the robot on it, moved {load[k]:.1f} kg in all "
                f"({what}), over the push limit of {limit:.1f} kg (a walk or a climb moves no more than a push may)"
            )
            found.setdefault(int(worlds[k]), (reason, float(load[k])))
        return found

    def _swept(self, worlds: np.ndarray, objects: np.ndarray, touched: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """(k, nobject) m the arc each object carried (``objects`` (k,)) or touched (``touched`` (k, nobject)) in
        ``worlds`` swept about the vertical since the ride began (its orientation then: ``frames``), else 0: a light
        mat turned in place on a 20 kg plank on a post swung the plank round under it (found by an adversarial run)."""
        out = np.zeros(touched.shape)
        watched = touched.copy()
        watched[np.arange(len(worlds)), objects] = True
        k, o = np.nonzero(watched)
        out[k, o] = self.senses.sweeps(worlds[k], o, frames[worlds[k], o], TURN)
        return out
