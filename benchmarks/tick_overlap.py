"""Would stepping one half of the worlds while the controller ticks the other half pay? A model of the schedule.

The lockstep runner steps every world one control interval on its thread pool, then ticks the controller for all of
them on the main thread while the pool waits. The alternative measured here splits the worlds into two groups: a
helper thread steps one group while the main thread ticks the other, then helps step. The controller is not run:
a busy loop of Python stands in for a tick (``--tick-ms`` for all the worlds, ``--half-tick-ms`` for one group; the
defaults are the quadruped's measured costs at 64 worlds, 0.76 s and 0.52 s over a pass of 383 ticks). The physics
is the quadruped's sofa_climbing scene in ``MujocoSim``'s own per-world models, stepped with ``mj_step``, as the
runner steps it.

Printed: milliseconds per control interval of all the worlds for the physics alone, for the runner's schedule
(physics, then one tick) and for the two-group schedule at several GIL switch intervals. The two-group schedule pays
only where it beats the runner's.

    python benchmarks/tick_overlap.py [--worlds 64] [--cycles 100] [--tick-ms 2.0] [--half-tick-ms 1.4]
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor

import mujoco

from robotool import sim, tasks
from robotool.sim.backend import Perturbation
from robotool.sim.backend_mujoco import MujocoSim

SWITCH_INTERVALS = (0.005, 0.001, 0.0002, 0.00005)  # s: Python's default first


def busy(seconds: float) -> None:
    """Run Python bytecode (holding the GIL) for ``seconds``: a stand-in for the controller's tick."""
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


class Stepper:
    """Steps chunks of worlds of one ``MujocoSim`` one control interval, taken in turn by any thread that asks."""

    def __init__(self, simulator: MujocoSim, nstep: int):
        self.sim, self.nstep = simulator, nstep

    def drain(self, worlds: Iterator[int], lock: threading.Lock) -> None:
        while True:
            with lock:
                w = next(worlds, None)
            if w is None:
                return
            data = self.sim.datas[w]
            data.ctrl[:] = self.sim.ctrl[w]
            mujoco.mj_step(self.sim.models[w], data, self.nstep)

    def step(self, worlds: range, pool: ThreadPoolExecutor, python_first: float = 0.0) -> None:
        """Step ``worlds`` on the helper and this thread; this thread first runs ``python_first`` s of Python."""
        lock, queue = threading.Lock(), iter(worlds)
        helper = pool.submit(self.drain, queue, lock)
        busy(python_first)
        self.drain(queue, lock)
        helper.result()


def per_cycle(cycles: int, one: Callable[[], object]) -> float:
    """Milliseconds per call of ``one``, over ``cycles`` calls."""
    start = time.perf_counter()
    for _ in range(cycles):
        one()
    return (time.perf_counter() - start) / cycles * 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", type=int, default=64)
    parser.add_argument("--cycles", type=int, default=100)
    parser.add_argument("--tick-ms", type=float, default=2.0, help="one tick of all the worlds")
    parser.add_argument("--half-tick-ms", type=float, default=1.4, help="one tick of half of them")
    args = parser.parse_args()
    scene = sim.build(tasks.load("sofa_climbing"))
    n = args.worlds
    simulator = MujocoSim(scene, n, Perturbation.sample(scene, n, 0), njmax=2000, nconmax=500)
    stepper = Stepper(simulator, scene.control_substeps)
    tick, half = args.tick_ms / 1000, args.half_tick_ms / 1000
    first, second = range(n // 2), range(n // 2, n)
    with ThreadPoolExecutor(1) as pool:
        physics = per_cycle(args.cycles, lambda: stepper.step(range(n), pool))
        runner = per_cycle(args.cycles, lambda: (stepper.step(range(n), pool), busy(tick)))
        print(
            f"{n} worlds, ms per control interval: physics alone {physics:.2f}; runner (physics, then a tick of "
            f"{args.tick_ms} ms) {runner:.2f}"
        )
        default = sys.getswitchinterval()
        try:
            for interval in SWITCH_INTERVALS:
                sys.setswitchinterval(interval)
                grouped = per_cycle(
                    args.cycles, lambda: (stepper.step(first, pool, half), stepper.step(second, pool, half))
                )
                print(
                    f"  two groups, a {args.half_tick_ms} ms tick of one while the other steps, GIL switch "
                    f"interval {interval * 1e6:.0f} us: {grouped:.2f}"
                )
        finally:
            sys.setswitchinterval(default)
    simulator.close()


if __name__ == "__main__":
    main()
