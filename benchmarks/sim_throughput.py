"""World-steps per second of the lockstep runner on a real arm task, next to raw stepping.

For each nworld, the runner executes the button_pressing reference program in nworld perturbed
worlds; raw ``mujoco.rollout`` (2 threads) and raw ``mjw.step`` (captured graph) step the same model
for the same number of steps. Prints a Markdown table with runner/raw.

The program runs as a trusted callable, :func:`button_pressing`, so that the table measures the
runner and not the sandbox (``benchmarks/sandbox_overhead.py`` measures that). It is a port of the
reference program file ``tests/fixtures/programs/button_pressing.py``; before timing, both are run in a
few worlds and must give identical rollouts.

    python benchmarks/sim_throughput.py                       # nworld 1, 16, 64, 256; both backends
    python benchmarks/sim_throughput.py --sizes 1 16 --backends mujoco
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from mujoco import rollout

from robotool import sim, tasks
from robotool.sandbox import start_sessions

TASK = "button_pressing"
PROGRAM_FILE = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "programs" / "button_pressing.py"


def button_pressing(robot: Any) -> None:
    """PROGRAM_FILE as a trusted callable: chain the magnetic cubes into a stick, press the button."""
    clear, lift = 0.08, 0.004
    g = robot.get_graspable_point("magnetic_cube_1")
    robot.open_gripper()
    robot.move_to_position([g[0], g[1], g[2] + clear])
    robot.move_to_position(g)
    robot.close_gripper()
    edge = robot.get_size("magnetic_cube_1")[0]
    z = g[2] + lift
    robot.move_to_position([g[0], g[1], z])
    for k, name in enumerate(("magnetic_cube_2", "magnetic_cube_3"), start=1):
        c = robot.get_center(name)
        robot.move_to_position([c[0] - k * edge - 0.05, c[1], z])
        robot.move_to_position([c[0] - k * edge + 0.004, c[1], z])
    button, bsize = robot.get_center("button"), robot.get_size("button")
    face = button[0] - bsize[0] / 2
    tip = 2.5 * edge
    height = button[2] + edge / 2
    robot.move_to_position([g[0], g[1], height + 0.03])
    robot.move_to_position([face - tip - 0.08, button[1], height + 0.03])
    robot.move_to_position([face - tip - 0.08, button[1], height])
    robot.move_to_position([face - tip + 0.02, button[1], height])


def check_port(scene: sim.Scene, nworld: int = 3) -> None:
    """The trusted port and the sandboxed program file must roll out identically."""
    trusted = sim.run_programs(scene, [button_pressing] * nworld, seed=0)
    sandboxed = sim.run_sessions(scene, start_sessions([PROGRAM_FILE.read_text()] * nworld, "arm"), seed=0)
    if [r.model_dump() for r in trusted] != [r.model_dump() for r in sandboxed]:
        raise SystemExit(f"button_pressing() no longer matches {PROGRAM_FILE}")


def runner_rate(scene: sim.Scene, nworld: int, backend: str) -> tuple[float, int]:
    """(world-steps/s, mean physics steps per world) of run_programs; a world stops when its program ends."""
    start = time.perf_counter()
    rollouts = sim.run_programs(scene, [button_pressing] * nworld, seed=0, backend=backend)
    wall = time.perf_counter() - start
    if backend == "warp":  # the warp batch steps every world until the last program ends
        steps = nworld * round((max(r.sim_time for r in rollouts) + sim.runner.SETTLE_TIME) / scene.model.opt.timestep)
    else:
        steps = sum(round((r.sim_time + sim.runner.SETTLE_TIME) / scene.model.opt.timestep) for r in rollouts)
    return steps / wall, steps // nworld


def raw_rollout_rate(scene: sim.Scene, nworld: int, nstep: int, nthread: int = 2) -> float:
    """``mujoco.rollout`` with one model copy per world (as the runner has), constant controls."""
    model = scene.model
    models = [model] * nworld
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.zeros(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    initial = np.tile(state, (nworld, 1))
    control = np.tile(data.ctrl, (nworld, nstep, 1))
    with rollout.Rollout(nthread=nthread) as runner:
        datas = [mujoco.MjData(model) for _ in range(nthread)]
        start = time.perf_counter()
        runner.rollout(models, datas, initial, control, nstep=nstep)
        return nworld * nstep / (time.perf_counter() - start)


def raw_warp_rate(scene: sim.Scene, nworld: int, nstep: int, substeps: int) -> float:
    """``mjw.step`` replayed from a graph of ``substeps`` steps (the runner's control interval)."""
    import mujoco_warp as mjw
    import warp as wp

    wp.config.quiet = True
    wp.config.log_level = wp.LOG_WARNING
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    m = mjw.put_model(model)
    d = mjw.put_data(model, data, nworld=nworld, nconmax=scene.nconmax, njmax=scene.njmax)

    def chunk() -> None:
        for _ in range(substeps):
            mjw.step(m, d)

    chunk()
    with wp.ScopedCapture() as capture:
        chunk()
    launches = max(1, nstep // substeps)
    start = time.perf_counter()
    for _ in range(launches):
        wp.capture_launch(capture.graph)
    wp.synchronize()
    return nworld * launches * substeps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 16, 64, 256])
    parser.add_argument("--backends", nargs="+", default=["mujoco", "warp"], choices=["mujoco", "warp"])
    parser.add_argument("--repeat", type=int, default=3, help="best of this many interleaved runs")
    args = parser.parse_args()
    scene = sim.build(tasks.load(TASK))
    check_port(scene)
    print(f"task {TASK}: nq={scene.model.nq}, ngeom={scene.model.ngeom}, "
          f"control every {scene.control_substeps} steps of {scene.model.opt.timestep} s\n")
    print("| backend | nworld | runner (world-steps/s) | raw (world-steps/s) | runner/raw |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for backend in args.backends:
        for nworld in args.sizes:
            rate, raw = 0.0, 0.0
            for _ in range(args.repeat):  # interleaved, so both see the same machine load
                run, steps = runner_rate(scene, nworld, backend)
                if backend == "mujoco":
                    base = raw_rollout_rate(scene, nworld, steps)
                else:
                    base = raw_warp_rate(scene, nworld, steps, scene.control_substeps)
                rate, raw = max(rate, run), max(raw, base)
            label = "mujoco (vs rollout, 2 threads)" if backend == "mujoco" else "warp (vs mjw.step graph)"
            print(f"| {label} | {nworld} | {rate:,.0f} | {raw:,.0f} | {rate / raw:.2f} |", flush=True)


if __name__ == "__main__":
    main()
