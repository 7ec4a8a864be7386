"""Keep the states of chosen worlds during a run, for pictures and videos made after it.

The runner calls :meth:`StateRecorder.capture` once after the settle phase and once per control tick
when a recorder is passed in; runs without one do no extra work. Only the generalized positions
(``qpos``, ``mocap_pos``) of the requested worlds are kept, with each world's time since its program
started, and a world's state is kept only when its time moved on (ended worlds are not stepped).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from robotool.sim.backend import BatchState


@dataclass
class Track:
    """The recorded states of one world: times in seconds since its program started, and positions."""

    times: list[float] = field(default_factory=list)
    qpos: list[np.ndarray] = field(default_factory=list)
    mocap_pos: list[np.ndarray] = field(default_factory=list)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(times (T,), qpos (T, nq), mocap_pos (T, nmocap, 3)) as arrays."""
        return np.asarray(self.times), np.asarray(self.qpos), np.asarray(self.mocap_pos)

    def __len__(self) -> int:
        return len(self.times)


class StateRecorder:
    """Records the states of ``worlds`` (batch indices) during one run of the lockstep runner."""

    def __init__(self, worlds: Iterable[int]):
        self.tracks: dict[int, Track] = {int(w): Track() for w in worlds}
        self._t0: np.ndarray | None = None

    def start(self, state: BatchState, mocap_pos: np.ndarray) -> None:
        """Begin at the state the programs start from (after the settle phase)."""
        nworld = len(state.time)
        outside = [w for w in self.tracks if not 0 <= w < nworld]
        if outside:
            raise ValueError(f"cannot record world(s) {outside}: the run has {nworld} world(s)")
        self._t0 = state.time.copy()
        self.capture(state, mocap_pos)

    def capture(self, state: BatchState, mocap_pos: np.ndarray) -> None:
        """Keep the requested worlds' positions when their time moved on since the last capture."""
        if self._t0 is None:
            raise RuntimeError("capture() before start()")
        for w, track in self.tracks.items():
            t = float(state.time[w] - self._t0[w])
            if track.times and t <= track.times[-1]:
                continue
            track.times.append(t)
            track.qpos.append(state.qpos[w].copy())
            track.mocap_pos.append(np.array(mocap_pos[w], dtype=float))
