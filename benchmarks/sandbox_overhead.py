"""What the sandbox costs: worker start-up, a skill call's round trip, and a whole arm rollout.

The rollout runs one program in N worlds through the real lockstep runner twice, as a trusted
callable and as sandboxed code, alternating, and reports the best and median wall times of each
and the ratio of the bests (on a shared machine the best runs are the fairest comparison). It also
reports the CPU seconds each form used (host threads, plus the zygote and its workers for the
sandbox), which other load on the machine disturbs much less than wall time. Both forms must
produce identical rollouts, which shows they are the same program.

    python benchmarks/sandbox_overhead.py [--worlds 64] [--repeats 5] [--task milk_reaching_near]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable
from typing import Any

from robotool import tasks
from robotool.program_session import ProgramEnded, SkillReply, SkillRequest
from robotool.sandbox import SandboxSession, start_sessions
from robotool.sandbox.zygote import zygote
from robotool.sim import build, run_programs, run_sessions

CODE = """\
p = get_graspable_point("milk")
open_gripper()
move_to_position([p[0], p[1], p[2] + 0.08])
move_to_position(p)
close_gripper()
move_to_position([p[0], p[1], p[2] + 0.05])
"""


def trusted(robot: Any) -> None:
    """CODE, as a trusted callable."""
    p = robot.get_graspable_point("milk")
    robot.open_gripper()
    robot.move_to_position([p[0], p[1], p[2] + 0.08])
    robot.move_to_position(p)
    robot.close_gripper()
    robot.move_to_position([p[0], p[1], p[2] + 0.05])


def timed(run: Callable[[], Any]) -> tuple[float, Any]:
    start = time.perf_counter()
    result = run()
    return time.perf_counter() - start, result


def cpu_seconds() -> float:
    """CPU time of this process and of the zygote with its reaped workers."""
    with open(f"/proc/{zygote().process.pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    sandbox = sum(int(f) for f in fields[11:15]) / os.sysconf("SC_CLK_TCK")  # utime stime cutime cstime
    host = os.times()
    return host.user + host.system + sandbox


def rollout(run: Callable[[], Any]) -> tuple[float, float, Any]:
    """Wall seconds, CPU seconds (counting workers reaped just after) and the rollouts."""
    cpu = cpu_seconds()
    wall, result = timed(run)
    time.sleep(0.3)
    return wall, cpu_seconds() - cpu, result


def startup(worlds: int) -> float:
    """Seconds per session for start_sessions with a warm zygote, sessions then closed."""
    seconds, sessions = timed(lambda: start_sessions([CODE] * worlds, "arm"))
    for s in sessions:
        s.close()
    return seconds / worlds


def round_trip(worlds: int, calls: int) -> float:
    """Seconds per query call answered at once, all worlds resumed before any is waited on."""
    code = f"for i in range({calls}):\n    get_center('milk')\n"
    sessions = start_sessions([code] * worlds, "arm")
    start = time.perf_counter()
    for s in sessions:
        s.resume(None)
    live: list[SandboxSession] = sessions
    while live:
        waiting = []
        for s in live:
            message = s.wait()
            if isinstance(message, SkillRequest):
                s.resume(SkillReply(value=[0.3, 0.0, 0.1]))
                waiting.append(s)
            else:
                assert isinstance(message, ProgramEnded) and message.error is None, message
        live = waiting
    seconds = time.perf_counter() - start
    for s in sessions:
        s.close()
    return seconds / (worlds * calls)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worlds", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--task", default="milk_reaching_near")
    args = parser.parse_args()

    first, _ = timed(lambda: start_sessions([CODE], "arm")[0].close())
    print(f"zygote start and first worker: {first * 1e3:.0f} ms")
    print(zygote().layers().summary())
    forking = startup(args.worlds)
    time.sleep(1.0)  # the zygote pre-forks spares for the next batch of this size while idle
    print(
        f"worker start-up, {args.worlds} at once: {forking * 1e3:.2f} ms per session forking on demand, "
        f"{startup(args.worlds) * 1e3:.2f} ms from pre-forked spares"
    )
    trip = round_trip(args.worlds, 50)
    print(f"skill call round trip: {trip * 1e6:.0f} us per call ({args.worlds} workers)")

    scene = build(tasks.load(args.task))
    walls: dict[str, list[float]] = {"trusted": [], "sandboxed": []}
    cpus: dict[str, list[float]] = {"trusted": [], "sandboxed": []}
    for _ in range(args.repeats):
        tw, tc, a = rollout(lambda: run_programs(scene, [trusted] * args.worlds, seed=1))
        sw, sc, b = rollout(lambda: run_sessions(scene, start_sessions([CODE] * args.worlds, "arm"), seed=1))
        assert [r.model_dump() for r in a] == [r.model_dump() for r in b], "the two forms disagree"
        for form, wall, cpu in (("trusted", tw, tc), ("sandboxed", sw, sc)):
            walls[form].append(wall)
            cpus[form].append(cpu)
    successes = sum(r.success for r in b)
    print(f"{args.task}, {args.worlds} worlds, {successes} succeeded, {args.repeats} runs each")
    median = statistics.median
    for form in walls:
        print(
            f"{form:9s}: wall best {min(walls[form]):.2f} s, median {median(walls[form]):.2f} s; "
            f"CPU median {median(cpus[form]):.2f} s"
        )
    print(
        f"ratio, wall best/best: {min(walls['sandboxed']) / min(walls['trusted']):.3f}; "
        f"CPU median/median: {median(cpus['sandboxed']) / median(cpus['trusted']):.3f}"
    )


if __name__ == "__main__":
    main()
