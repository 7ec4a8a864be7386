"""Per-body arrays summed over each object's bodies (a cloth: its links), for the quadruped's referee: the sums
``np.einsum`` with the objects' membership matrix gives, to the bit, at a small share of its cost (it runs over
every body of every object, most of them zeros)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ObjectSums:
    """Sums over the bodies of each object, added one body at a time in ascending order from zero, as ``np.einsum``
    adds them (the other bodies' terms are zeros: they change no sum); a zero sums to +0, as there."""

    member: np.ndarray  # (nobject, nbody) 1.0 where a body is the object's, else 0.0
    bodies: tuple[np.ndarray, ...]  # each object's bodies, ascending
    first: np.ndarray  # (nobject,) each object's first body (0: it has none)
    empty: np.ndarray  # the objects with no body (each sum zero)
    extra: tuple[tuple[np.ndarray, np.ndarray], ...]  # for the r-th further body: the objects with one, and that body
    pairs_exact: bool  # no two objects have several bodies: :meth:`pairs` sums each cross pair as the einsum does

    @classmethod
    def of(cls, member: np.ndarray) -> ObjectSums:
        bodies = tuple(np.flatnonzero(row) for row in member)
        extra = []
        for rank in range(1, max((len(b) for b in bodies), default=1)):
            objects = np.array([o for o, b in enumerate(bodies) if len(b) > rank])
            extra.append((objects, np.array([bodies[o][rank] for o in objects])))
        return cls(
            member=member,
            bodies=bodies,
            first=np.array([b[0] if len(b) else 0 for b in bodies], dtype=int),
            empty=np.array([o for o, b in enumerate(bodies) if not len(b)], dtype=int),
            extra=tuple(extra),
            pairs_exact=sum(len(b) > 1 for b in bodies) <= 1,
        )

    def rows(self, values: np.ndarray) -> np.ndarray:
        """(nobject, ...) ``values`` (nbody, ...) summed over each object's bodies: ``einsum("ob,b...->o...")``."""
        out = values[self.first] + 0.0
        out[self.empty] = 0.0
        for objects, bodies in self.extra:
            out[objects] = out[objects] + values[bodies]
        return out

    def pairs(self, values: np.ndarray) -> np.ndarray:
        """(nobject, nobject, 3) ``values`` (nbody, nbody, 3) summed over the bodies of each pair of objects:
        ``einsum("ab,bcx,dc->adx")``. An object's pair with itself (a cloth's links among themselves) may differ
        from it by rounding: for contact normals, antisymmetric, that is a residue of cancelled sums (far below any
        threshold read); with two objects of several bodies it is the einsum itself."""
        if not self.pairs_exact:
            return np.einsum("ab,bcx,dc->adx", self.member, values, self.member)
        return self.rows(self.rows(values).swapaxes(0, 1)).swapaxes(0, 1)
