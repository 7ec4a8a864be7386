"""World-steps per second of the lockstep runner on a real arm task, next to raw stepping of the same physics.

For each embodiment and nworld, the runner executes a reference program in nworld perturbed worlds: the arm's
button_pressing and the quadruped's sofa_climbing.
A recording pass (untimed, same seeds) wraps the backend's ``step`` and records each world's initial
state, the ctrl, ``xfrc_applied`` and ``eq_active`` applied to every active world at every ``step(nstep, active)`` call,
and the per-world weld ``eq_data`` (relative poses set at attach time). The raw baselines replay exactly
that physics:

- ``mujoco``: ``mujoco.rollout`` (2 threads), one model copy per world (the runner's own copies:
  perturbed friction/mass/inertia and final ``eq_data``),
  ``control_spec=mjSTATE_CTRL|mjSTATE_XFRC_APPLIED|mjSTATE_EQ_ACTIVE``.
  A world that the runner stops early gets a NaN ctrl at its last step + 1, where rollout stops
  stepping it (MuJoCo's bad-ctrl warning; so it does one uncounted extra step).
- ``warp``: a fresh ``WarpSim`` with the same perturbation and the final ``eq_data``; a captured graph of
  one control interval (a kernel writes the tick's recorded ctrl/``xfrc_applied``/``eq_active`` from device arrays, then
  ``mjw.step`` x substeps, then bumps the tick), launched once per recorded tick. Graph capture is
  outside the timing (the runner captures its graphs inside each run).

Both sides count the same world-steps (the recorded ones). The replay is checked against the runner:
``eq_data`` of a weld must not change after it was first used (each weld attaches once), and the
replayed final qpos of every world is compared with the runner's (printed as max |dqpos|).
"raw, resting" is the former baseline: the unperturbed scene at rest under constant controls.

The program runs as a trusted callable (:func:`button_pressing`, :func:`sofa_climbing`), so that the table
measures the runner and not the sandbox (``benchmarks/sandbox_overhead.py`` measures that). Each is a port of
its reference program file in ``tests/fixtures/programs/``; before timing, both are run in a few worlds and
must give identical rollouts.

    python benchmarks/sim_throughput.py                       # nworld 1, 16, 64, 256; both backends, both robots
    python benchmarks/sim_throughput.py --sizes 64 --backends mujoco --embodiments arm quadruped
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from mujoco import rollout

from robotool import sim, tasks
from robotool.sandbox import start_sessions
from robotool.sim.backend import Perturbation
from robotool.sim.backend_choice import make_sim

PROGRAMS = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "programs"
FULLPHYSICS = mujoco.mjtState.mjSTATE_FULLPHYSICS
CONTROL_SPEC = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_EQ_ACTIVE
"""Laid out ctrl, xfrc_applied (nbody x 6), then eq_active."""


def button_pressing(robot: Any) -> None:
    """programs/button_pressing.py as a trusted callable: chain the magnetic cubes into a stick, press the button."""
    clear, lift = 0.08, 0.004
    g = robot.get_graspable_point("magnetic_cube1")
    robot.open_gripper()
    robot.move_to_position([g[0], g[1], g[2] + clear])
    robot.move_to_position(g)
    robot.close_gripper()
    edge = robot.get_size("magnetic_cube1")[0]
    z = g[2] + lift
    robot.move_to_position([g[0], g[1], z])
    for k, name in enumerate(("magnetic_cube2", "magnetic_cube3"), start=1):
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


def sofa_climbing(robot: Any) -> None:
    """programs/sofa_climbing.py as a trusted callable: push box_1 against box_2, climb them onto the sofa."""
    margin = 0.05
    box_1, size_1 = robot.get_position("box_1"), robot.get_size("box_1")
    box_2, size_2 = robot.get_position("box_2"), robot.get_size("box_2")
    sofa, sofa_size = robot.get_position("sofa"), robot.get_size("sofa")
    step_x = box_2[0] - size_2[0] / 2 - size_1[0] / 2
    robot.push_to_position("box_1", [step_x, box_2[1], box_1[2]])
    robot_size = robot.get_size("robot")
    robot.walk_to_position([step_x - size_1[0] / 2 - robot_size[0] / 2 - margin, box_2[1], 0.0])
    robot.climb_to_position([sofa[0] + sofa_size[0] / 2 - robot_size[0] / 2 - margin, box_2[1], sofa[2]])


@dataclass(frozen=True)
class Case:
    """An embodiment's benchmark: a built-in task and its reference program, trusted and as a file."""

    task: str
    program: Callable[[Any], None]
    embodiment: str

    @property
    def file(self) -> Path:
        return PROGRAMS / f"{self.task}.py"


CASES = {
    "arm": Case("button_pressing", button_pressing, "arm"),
    "quadruped": Case("sofa_climbing", sofa_climbing, "quadruped"),
}


def check_port(scene: sim.Scene, case: Case, nworld: int = 3) -> None:
    """The trusted port and the sandboxed program file must roll out identically."""
    trusted = sim.run_programs(scene, [case.program] * nworld, seed=0)
    sandboxed = sim.run_sessions(scene, start_sessions([case.file.read_text()] * nworld, case.embodiment), seed=0)
    if [r.model_dump() for r in trusted] != [r.model_dump() for r in sandboxed]:
        raise SystemExit(f"{case.program.__name__}() no longer matches {case.file}")


# -- recording ---------------------------------------------------------------------------------------


@dataclass
class Recording:
    """What one runner pass applied to the physics, per ``step(nstep, active)`` call."""

    backend: str
    sim: Any = None
    initial: np.ndarray | None = None  # (nworld, nstate) full physics state before the first step (mujoco)
    warmstart: np.ndarray | None = None  # (nworld, nv) qacc_warmstart before the first step (mujoco)
    calls: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)  # nstep,
    # worlds, ctrl (len(worlds), nu), xfrc_applied (len(worlds), nbody * 6), eq_active (len(worlds), neq)
    first_eq_data: np.ndarray | None = None  # (nworld, neq, neqdata) value of each weld when first active
    eq_data_changed: np.ndarray | None = None  # (nworld, neq) changed while active after first use

    def observe(self, s: Any, nstep: int, active: np.ndarray) -> None:
        if self.sim is None:
            self.sim = s
            if self.backend == "mujoco":
                size = mujoco.mj_stateSize(s.scene.model, FULLPHYSICS)
                self.initial = np.zeros((s.nworld, size))
                for w, (m, d) in enumerate(zip(s.models, s.datas, strict=True)):
                    mujoco.mj_getState(m, d, self.initial[w], FULLPHYSICS)
                self.warmstart = np.array([d.qacc_warmstart for d in s.datas])
        if self.backend == "mujoco":
            worlds = np.flatnonzero(np.asarray(active) & np.array([f is None for f in s._failed]))
            eq_active = np.array([s.datas[w].eq_active for w in worlds], dtype=bool).reshape(len(worlds), -1)
            eq_data = np.array([m.eq_data for m in s.models])
        else:  # warp steps every world
            worlds = np.arange(s.nworld)
            eq_active = s.d.eq_active.numpy().astype(bool)
            eq_data = s._eq_data.copy()
        xfrc = s.xfrc_applied[worlds].reshape(len(worlds), -1).copy()
        self.calls.append((nstep, worlds, s.ctrl[worlds].copy(), xfrc, eq_active))
        if self.first_eq_data is None:
            self.first_eq_data = np.full_like(eq_data, np.nan)
            self.eq_data_changed = np.zeros(eq_data.shape[:2], dtype=bool)
        used = np.zeros(eq_data.shape[:2], dtype=bool)
        used[worlds] = eq_active
        new = used & np.isnan(self.first_eq_data[:, :, 0])
        self.first_eq_data[new] = eq_data[new]
        self.eq_data_changed |= used & (eq_data != self.first_eq_data).any(axis=2)

    @property
    def steps(self) -> np.ndarray:
        """Physics steps per world."""
        steps = np.zeros(self.sim.nworld, dtype=int)
        for nstep, worlds, *_ in self.calls:
            steps[worlds] += nstep
        return steps

    def final_eq_data(self) -> np.ndarray:
        if self.backend == "mujoco":
            return np.array([m.eq_data for m in self.sim.models])
        return self.sim._eq_data.copy()

    def reattached(self) -> int:
        """(world, weld) pairs whose eq_data changed after the weld was first used, or differs from the final."""
        seen = ~np.isnan(self.first_eq_data[:, :, 0])
        final = self.final_eq_data()
        differs = seen & (np.nan_to_num(self.first_eq_data) != final).any(axis=2)
        return int((self.eq_data_changed | differs).sum())

    def final_qpos(self) -> np.ndarray:
        return self.sim.state().qpos.copy()


@contextlib.contextmanager
def recording(backend: str) -> Iterator[Recording]:
    """Wrap the backend class's ``step`` so that every call is recorded (untimed passes only)."""
    if backend == "mujoco":
        from robotool.sim.backend_mujoco import MujocoSim as cls
    else:
        from robotool.sim.backend_warp import WarpSim as cls
    original = cls.step
    rec = Recording(backend)

    def step(self: Any, nstep: int, active: np.ndarray) -> None:
        rec.observe(self, nstep, active)
        original(self, nstep, active)

    cls.step = step  # type: ignore[method-assign]
    try:
        yield rec
    finally:
        cls.step = original  # type: ignore[method-assign]


def runner_pass(scene: sim.Scene, case: Case, nworld: int, backend: str) -> tuple[float, list[float]]:
    """(wall seconds, sim_time per world) of one run_programs pass; a world stops when its program ends."""
    start = time.perf_counter()
    rollouts = sim.run_programs(scene, [case.program] * nworld, seed=0, backend=backend)
    return time.perf_counter() - start, [r.sim_time for r in rollouts]


def world_steps(recording: Recording) -> int:
    """World-steps of the recorded pass (warp steps every world until the last program ends)."""
    return int(recording.steps.sum())


# -- C replay ------------------------------------------------------------------------------------------


@dataclass
class RolloutReplay:
    models: list[mujoco.MjModel]
    initial: np.ndarray
    warmstart: np.ndarray
    control: np.ndarray  # (nworld, nstep, nu + nbody * 6 + neq)
    steps: np.ndarray
    state: np.ndarray  # output buffers, allocated once
    sensordata: np.ndarray


def rollout_replay(rec: Recording) -> RolloutReplay:
    s = rec.sim
    model = s.scene.model
    steps = rec.steps
    length = int(steps.max())
    xfrc_end = model.nu + model.nbody * 6
    control = np.zeros((s.nworld, length, xfrc_end + model.neq))
    pos = np.zeros(s.nworld, dtype=int)
    for nstep, worlds, ctrl, xfrc, eq_active in rec.calls:
        if not worlds.size:
            continue
        p = pos[worlds[0]]
        if (pos[worlds] != p).any():
            raise SystemExit("active worlds out of step: cannot replay as one rollout")
        control[worlds, p : p + nstep, : model.nu] = ctrl[:, None]
        control[worlds, p : p + nstep, model.nu : xfrc_end] = xfrc[:, None]
        control[worlds, p : p + nstep, xfrc_end:] = eq_active[:, None]
        pos[worlds] += nstep
    short = np.flatnonzero(steps < length)
    control[short, steps[short], 0] = np.nan  # bad ctrl: rollout stops this world after one more step
    nstate = mujoco.mj_stateSize(model, FULLPHYSICS)
    return RolloutReplay(
        models=s.models,
        initial=rec.initial,
        warmstart=rec.warmstart,
        control=control,
        steps=steps,
        state=np.zeros((s.nworld, length, nstate)),
        sensordata=np.zeros((s.nworld, length, model.nsensordata)),
    )


def rollout_replay_rate(rep: RolloutReplay, nthread: int = 2) -> float:
    """World-steps/s of ``mujoco.rollout`` replaying the recorded physics (recorded steps counted)."""
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda _msg: None)  # the stop markers' bad-ctrl warnings (no log file)
    try:
        with rollout.Rollout(nthread=nthread) as pool:
            datas = [mujoco.MjData(rep.models[0]) for _ in range(nthread)]
            start = time.perf_counter()
            pool.rollout(
                rep.models,
                datas,
                rep.initial,
                rep.control,
                control_spec=CONTROL_SPEC,
                nstep=rep.control.shape[1],
                initial_warmstart=rep.warmstart,
                state=rep.state,
                sensordata=rep.sensordata,
            )
            wall = time.perf_counter() - start
    finally:
        mujoco.set_mju_user_warning(previous)
    return int(rep.steps.sum()) / wall


def rollout_final_qpos(rep: RolloutReplay, nq: int) -> np.ndarray:
    last = rep.state[np.arange(len(rep.steps)), rep.steps - 1]
    return last[:, 1 : 1 + nq]  # full physics state: time, qpos, qvel, ...


def raw_rollout_resting_rate(scene: sim.Scene, nworld: int, nstep: int, nthread: int = 2) -> float:
    """``mujoco.rollout`` of the unperturbed scene from rest under constant controls (the former baseline)."""
    model = scene.model
    models = [model] * nworld
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    state = np.zeros(mujoco.mj_stateSize(model, FULLPHYSICS))
    mujoco.mj_getState(model, data, state, FULLPHYSICS)
    initial = np.tile(state, (nworld, 1))
    control = np.tile(data.ctrl, (nworld, nstep, 1))
    with rollout.Rollout(nthread=nthread) as runner:
        datas = [mujoco.MjData(model) for _ in range(nthread)]
        start = time.perf_counter()
        runner.rollout(models, datas, initial, control, nstep=nstep)
        return nworld * nstep / (time.perf_counter() - start)


# -- warp replay ---------------------------------------------------------------------------------------


@functools.cache
def _warp_kernels() -> tuple[Any, Any]:
    import warp as wp

    @wp.kernel
    def apply_tick(
        tick: wp.array(dtype=int),
        ctrl_all: wp.array3d(dtype=float),
        xfrc_all: wp.array3d(dtype=float),
        eq_all: wp.array3d(dtype=bool),
        ctrl: wp.array2d(dtype=float),
        xfrc_applied: wp.array2d(dtype=wp.spatial_vector),
        eq_active: wp.array2d(dtype=bool),
    ):
        w = wp.tid()
        t = tick[0]
        for j in range(ctrl.shape[1]):
            ctrl[w, j] = ctrl_all[t, w, j]
        for b in range(xfrc_applied.shape[1]):
            x = xfrc_all[t, w]
            k = 6 * b
            xfrc_applied[w, b] = wp.spatial_vector(x[k], x[k + 1], x[k + 2], x[k + 3], x[k + 4], x[k + 5])
        for j in range(eq_active.shape[1]):
            eq_active[w, j] = eq_all[t, w, j]

    @wp.kernel
    def next_tick(tick: wp.array(dtype=int)):
        wp.atomic_add(tick, 0, 1)  # (the body must name wp: annotations resolve from the closure)

    return apply_tick, next_tick


@dataclass
class WarpReplay:
    sim: Any
    graphs: dict[int, Any]
    ticks: list[int]  # nstep of each graph launch, in order
    tick: Any
    steps: int


def warp_replay(rec: Recording, scene: sim.Scene) -> WarpReplay:
    """A fresh WarpSim (same perturbation, the recorded final eq_data) and one graph per control interval."""
    import mujoco_warp as mjw
    import warp as wp

    apply_tick, next_tick = _warp_kernels()
    nworld, sub = rec.sim.nworld, scene.control_substeps
    ws = make_sim(scene, nworld, backend="warp", perturbation=Perturbation.sample(scene, nworld, 0))
    ticks, ctrl, xfrc, eq_active = [], [], [], []
    for nstep, _, c, x, e in rec.calls:  # a settle step of k control intervals replays as k ticks
        n, k = (sub, nstep // sub) if nstep % sub == 0 else (nstep, 1)
        ticks += [n] * k
        ctrl += [c] * k
        xfrc += [x] * k
        eq_active += [e] * k
    with wp.ScopedDevice(ws.device):
        ws.m.eq_data.assign(rec.final_eq_data())
        ctrl_all = wp.array(np.array(ctrl, dtype=np.float32))
        xfrc_all = wp.array(np.array(xfrc, dtype=np.float32))
        eq_all = wp.array(np.array(eq_active, dtype=bool))
        tick = wp.zeros(1, dtype=int)
        d, m = ws.d, ws.m

        def chunk(n: int) -> None:
            inputs = [tick, ctrl_all, xfrc_all, eq_all, d.ctrl, d.xfrc_applied, d.eq_active]
            wp.launch(apply_tick, dim=nworld, inputs=inputs)
            for _ in range(n):
                mjw.step(m, d)
            wp.launch(next_tick, dim=1, inputs=[tick])

        keys = ("qpos", "qvel", "act", "time", "qacc_warmstart", "ctrl", "xfrc_applied", "eq_active", "overflow")
        saved = {k: getattr(d, k).numpy().copy() for k in keys}
        graphs = {}
        for n in sorted(set(ticks)):
            chunk(n)  # loads the kernels
            with wp.ScopedCapture() as capture:
                chunk(n)
            graphs[n] = capture.graph
        for key, value in saved.items():
            getattr(d, key).assign(value)
    return WarpReplay(sim=ws, graphs=graphs, ticks=ticks, tick=tick, steps=nworld * sum(ticks))


def warp_replay_rate(rep: WarpReplay, saved: dict[str, np.ndarray]) -> float:
    import warp as wp

    d = rep.sim.d
    with wp.ScopedDevice(rep.sim.device):
        for key, value in saved.items():
            getattr(d, key).assign(value)
        rep.tick.zero_()
        wp.synchronize()
        start = time.perf_counter()
        for n in rep.ticks:
            wp.capture_launch(rep.graphs[n])
        wp.synchronize()
        wall = time.perf_counter() - start
    return rep.steps / wall


def raw_warp_resting_rate(scene: sim.Scene, nworld: int, nstep: int, substeps: int) -> float:
    """``mjw.step`` of the unperturbed resting scene from a graph of ``substeps`` steps (the former baseline)."""
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


# -- main ----------------------------------------------------------------------------------------------


def measure(scene: sim.Scene, case: Case, backend: str, nworld: int, repeat: int) -> str:
    """One table row: best of ``repeat`` interleaved runner / replay / resting passes."""
    with recording(backend) as rec:
        _, sim_times = runner_pass(scene, case, nworld, backend)
    steps = world_steps(rec)
    per_world = steps // nworld
    nq = scene.model.nq
    reattached = rec.reattached()
    expected = rec.final_qpos()
    if backend == "mujoco":
        rep = rollout_replay(rec)
    else:
        wrep = warp_replay(rec, scene)
        saved = {
            k: getattr(wrep.sim.d, k).numpy().copy()
            for k in ("qpos", "qvel", "act", "time", "qacc_warmstart", "ctrl", "xfrc_applied", "eq_active", "overflow")
        }
    run_rate, replay_rate, rest_rate, same = 0.0, 0.0, 0.0, True
    for _ in range(repeat):  # interleaved, so all see the same machine load
        wall, times = runner_pass(scene, case, nworld, backend)
        same &= times == sim_times
        run_rate = max(run_rate, steps / wall)
        if backend == "mujoco":
            replay_rate = max(replay_rate, rollout_replay_rate(rep))
            rest_rate = max(rest_rate, raw_rollout_resting_rate(scene, nworld, per_world))
        else:
            replay_rate = max(replay_rate, warp_replay_rate(wrep, saved))
            rest_rate = max(rest_rate, raw_warp_resting_rate(scene, nworld, per_world, scene.control_substeps))
    replayed = rollout_final_qpos(rep, nq) if backend == "mujoco" else wrep.sim.d.qpos.numpy().astype(float)
    dq = float(np.abs(replayed - expected).max())
    check = (
        f"{dq:.1e}"
        + ("" if same else ", runner passes differ!")
        + (f", {reattached} re-attached!" if reattached else "")
    )
    label = "mujoco (rollout, 2 thr)" if backend == "mujoco" else "warp (mjw.step graph)"
    return (
        f"| {case.embodiment}: {label} | {nworld} | {per_world:,} | {run_rate:,.0f} | {replay_rate:,.0f} | "
        f"{run_rate / replay_rate:.2f} | {rest_rate:,.0f} | {run_rate / rest_rate:.2f} | {check} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 16, 64, 256])
    parser.add_argument("--backends", nargs="+", default=["mujoco", "warp"], choices=["mujoco", "warp"])
    parser.add_argument("--repeat", type=int, default=3, help="best of this many interleaved runs")
    parser.add_argument("--embodiments", nargs="+", default=list(CASES), choices=list(CASES))
    args = parser.parse_args()
    cases = [CASES[name] for name in args.embodiments]
    scenes = [sim.build(tasks.load(case.task)) for case in cases]
    for case, scene in zip(cases, scenes, strict=True):
        check_port(scene, case)
        print(
            f"{case.embodiment}, task {case.task}: nq={scene.model.nq}, ngeom={scene.model.ngeom}, "
            f"control every {scene.control_substeps} steps of {scene.model.opt.timestep} s"
        )
    print(f"load average {os.getloadavg()[0]:.2f}\n")
    print(
        "| embodiment: backend (raw) | nworld | steps/world | runner (world-steps/s) | raw replay (world-steps/s) "
        "| runner/replay | raw, resting (world-steps/s) | runner/resting | replay max abs dqpos |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for backend in args.backends:
        for nworld in args.sizes:
            for case, scene in zip(cases, scenes, strict=True):
                print(measure(scene, case, backend, nworld, args.repeat), flush=True)
    print(f"\nload average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
