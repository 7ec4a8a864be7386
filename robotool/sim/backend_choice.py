"""``make_sim``: a batched simulator on the backend asked for, each backend imported only when first used."""

from __future__ import annotations

from typing import Protocol

from robotool.sim.backend import BatchedSim, Perturbation
from robotool.sim.compiled_scene import Scene
from robotool.vocabulary import BACKENDS, BackendName


def make_sim(
    scene: Scene,
    nworld: int,
    *,
    backend: BackendName = "mujoco",
    perturbation: Perturbation | None = None,
    njmax: int | None = None,
    nconmax: int | None = None,
) -> BatchedSim:
    """A batched simulator of ``nworld`` worlds on ``backend`` (``mujoco`` or ``warp``).

    ``njmax``/``nconmax`` (constraint rows and contacts per world) default to the scene's sizes;
    a world that needs more is marked failed.
    """
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; use one of {', '.join(BACKENDS)}")
    cls = _backend_class(backend)
    return cls(
        scene,
        nworld,
        perturbation or Perturbation.none(scene, nworld),
        njmax=njmax or scene.njmax,
        nconmax=nconmax or scene.nconmax,
    )


class _SimClass(Protocol):
    """A backend's simulator class, as :func:`make_sim` constructs it."""

    def __call__(
        self, scene: Scene, nworld: int, perturbation: Perturbation, *, njmax: int, nconmax: int
    ) -> BatchedSim: ...


def _backend_class(backend: BackendName) -> _SimClass:
    """The backend's simulator class, imported when first asked for (Warp takes seconds to load)."""
    if backend == "warp":
        from robotool.sim.backend_warp import WarpSim

        return WarpSim
    from robotool.sim.backend_mujoco import MujocoSim

    return MujocoSim
