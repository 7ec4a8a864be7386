"""What the quadruped's referee reads of a ram: which movable objects a pushed object presses, directly or through
others (:func:`pressed_by`), which of them are stuck to it (:func:`stuck_to`) or pressed along the push
(:func:`pressed_along`), which a moving carrier bears along (:func:`borne_along`), and the arcs what turns sweeps
about the vertical (:func:`turns`, :func:`side_swings`), which count as travel where a centre barely moves (a plank
swung round a post)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import bears_up
from robotool.sim.magnets import Magnets

RAM_ANGLE = np.radians(60.0)  # rad: contacts pressing within this of the push direction push what they touch along
SIDE_ANGLE = np.radians(30.0)  # rad: contacts pressing within this of horizontal press a side, whichever way it faces
RAM_PRESS = 0.5  # the least horizontal part of a presser's summed unit contact normals along the push that rams
STILL_CARRIER = 1e-5  # m a carrier may move in a tick and count as still (:func:`borne_along`)


def turns(senses: Senses, objects: np.ndarray, before: np.ndarray) -> np.ndarray:
    """(nworld, nobject) m the arc the farthest corner of each of ``objects`` swept about the vertical since its
    orientation ``before`` (:meth:`.Senses.sweeps`), else 0: a light mat under the feet of a robot turning in place
    turns with them while its centre stays (found by an adversarial run)."""
    out = np.zeros(objects.shape)
    worlds, index = np.nonzero(objects)
    if worlds.size:
        out[worlds, index] = senses.sweeps(worlds, index, before[worlds, index])
    return out


def side_swings(
    senses: Senses,
    met: np.ndarray,
    before: np.ndarray,
    normals_in: Callable[[int], np.ndarray],
    rammed_by: np.ndarray,
    pushing: np.ndarray,
) -> np.ndarray:
    """(nworld, nobject) m the arc the farthest corner of each rammed object pressed this tick (``met``) swept about
    the vertical since its orientation ``before`` (the last tick's; :meth:`.Senses.sweeps`: a light box rammed into one
    end of a 20 kg plank on a post swung the plank into line over a gap while its centre moved under 3 cm, found by an
    adversarial run), where a movable object presses one of its sides, or it bears up the object pushed (``pushing``
    (nworld,), -1: none) or one that push rams on its side (``rammed_by`` (nworld, nobject)): a box pushed along the
    plank's top, or rammed there by another, drags it round by friction (found by later runs). ``normals_in(w)``: the
    summed contact normals between the objects in world ``w``. What turns only under a load that presses it down, on
    what bears it up, or once nothing presses it, counts by its centre alone (a board whose cube rides on it turns as a
    chair pushed out from under its raised end lets it down)."""
    swings = np.zeros(met.shape)
    for w in np.flatnonzero(met.any(axis=1)).tolist():
        normals = normals_in(w)  # (nobject, nobject, 3) from each object onto each other
        movable = normals[senses.facts.movable]
        touched = np.linalg.norm(movable, axis=2) > 0
        sides = (touched & ~bears_up(movable) & ~bears_up(-movable)).any(axis=0)
        group = np.flatnonzero(sides & (rammed_by[w] == pushing[w])) if pushing[w] >= 0 else np.zeros(0, dtype=int)
        group = np.append(group, pushing[w]) if pushing[w] >= 0 else group
        objects = np.flatnonzero(met[w])
        under = bears_up(normals[objects][:, group]).any(axis=1) if group.size else np.zeros(len(objects), dtype=bool)
        objects = objects[sides[objects] | under]
        swings[w, objects] = senses.sweeps(np.full(len(objects), w), objects, before[w, objects])
    return swings


def stuck_to(
    senses: Senses, magnets: Magnets, worlds: np.ndarray, index: np.ndarray, pressed: np.ndarray
) -> np.ndarray:
    """(k, nobject) the ``pressed`` objects stuck (a magnet's weld) to object ``index[i]`` or to another pressed
    object in world ``worlds[i]``: they go wherever it is pushed."""
    owner = senses.scene.body_object
    group = pressed.copy()
    group[np.arange(len(worlds)), index] = True
    out = np.zeros(pressed.shape, dtype=bool)
    for eq, b1, b2 in magnets.pairs:
        active = senses.state.eq_active[worlds, eq]
        out[:, owner[b2]] |= active & group[:, owner[b1]]
        out[:, owner[b1]] |= active & group[:, owner[b2]]
    return out & pressed


def pressed_by(senses: Senses, worlds: np.ndarray, index: np.ndarray) -> np.ndarray:
    """(k, nobject) the movable objects that object ``index[i]`` touches in world ``worlds[i]``, directly or
    through other movable objects (itself left out)."""
    member = senses.facts.bodies
    touch = ((member @ senses.state.touching[worlds] @ member.T) > 0).astype(float)  # counts: exact
    own = np.arange(len(senses.scene.object_names))[None, :] == np.asarray(index)[:, None]
    group = own.copy()
    while True:
        near = (group.astype(float)[:, None, :] @ touch)[:, 0] > 0
        added = near & senses.facts.movable & ~group
        if not added.any():
            return group & ~own
        group |= added


def borne_along(senses: Senses, asked: np.ndarray, travel: np.ndarray) -> np.ndarray:
    """(nworld, nobject) which of the objects ``asked`` (nworld, nobject) a movable object that moved this tick
    (``travel`` (nworld, nobject) m, in 3-D) bears up (:func:`~.support.bears_up`): it goes where its carrier takes it
    (a cube on a lever's board as the board tips)."""
    borne = np.zeros(asked.shape, dtype=bool)
    for w in np.flatnonzero(asked.any(axis=1)).tolist():
        normals = senses.facts.sums.pairs(senses.sim.contact_normals(w))  # (nobject, nobject, 3) from one onto another
        carriers = senses.facts.movable & (travel[w] > STILL_CARRIER)
        for index in np.flatnonzero(asked[w]).tolist():
            borne[w, index] = bool((carriers & bears_up(normals[:, index])).any())
    return borne


def pressed_along(normals: np.ndarray, index: int, pressed: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(nobject,) the ``pressed`` objects that object ``index`` or another pressed object presses on along ``u``
    (x-y) or aside in a world whose objects press on each other along ``normals`` (:meth:`Referee._object_normals`): for
    one of them, the horizontal part of the summed normals of its contacts with the object is at least
    :data:`RAM_PRESS` and points within :data:`RAM_ANGLE` of ``u``, or lies within :data:`SIDE_ANGLE` of
    horizontal (it presses a flank or a slanted face: a hook's tip wedging a crate out of its way moves it as
    surely as its face does). Each presser is judged alone, by its horizontal part, so that what lies on the
    object (pressing down) or under it (carrying it, on a tilted board too) neither hides a push nor makes one.
    What bears the object up (:func:`~.support.bears_up`) is dragged along under it, pressed down: a bar rolling
    under a pushed board's raised end goes where the push takes it."""
    pressers = pressed.copy()
    pressers[index] = True
    pressing = normals[pressers]  # (npresser, nobject, 3)
    flat = np.linalg.norm(pressing[:, :, :2], axis=2)
    along = pressing[:, :, :2] @ u
    aside = flat > np.cos(SIDE_ANGLE) * np.linalg.norm(pressing, axis=2)
    under = bears_up(normals[:, index])  # (nobject,) pressing the object up
    return pressed & (((flat >= RAM_PRESS) & ((along > np.cos(RAM_ANGLE) * flat) | aside)).any(axis=0) | under)
