"""Sandboxed sessions under a fake lockstep runner, and the hostile-program corpus.

The fake runner answers like the real one is specified to: it resumes every world, collects each
world's next request, answers queries at once with canned values, then "simulates" (optionally
sleeping) and answers every pending motion together.
"""

from __future__ import annotations

import os
import signal
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from fixtures.paths import FIXTURES

from robotool import robots
from robotool.program_session import ProgramEnded, SkillReply, SkillRequest, wait_all
from robotool.sandbox import SandboxLimits, SandboxSession, start_sessions, validate
from robotool.sandbox.validate import ProgramRejected
from robotool.sandbox.zygote import Zygote, zygote

HOSTILE = sorted((FIXTURES / "hostile").glob("*.py"))
CANARY = Path("/tmp/robotool-sandbox-canary")
FAST = SandboxLimits(cpu_s=0.5, wall_s=20.0, memory_mb=128, max_output_chars=5_000, max_skill_calls=50)
QUERY_VALUES: dict[str, object] = {
    "get_center": [0.3, 0.0, 0.1],
    "get_graspable_point": np.array([0.3, 0.0, 0.135]),
    "get_size": (0.044, 0.044, 0.16),
    "get_workspace_range": [[-0.3, 0.45], [-0.45, 0.45], [0.0, 0.5]],
}
QUERIES = {s.name for s in robots.get("arm").skills if s.kind == "query"}

GRASP = """\
import numpy as np
p = np.array(get_graspable_point("milk"))
print("grasp point", p.tolist())
open_gripper()
move_to_position(p + [0.0, 0.0, 0.1])
move_to_position(p)
close_gripper()
"""
GRASP_MOTIONS = [
    ("open_gripper", ()),
    ("move_to_position", ((0.3, 0.0, 0.235),)),
    ("move_to_position", ((0.3, 0.0, 0.135),)),
    ("close_gripper", ()),
]


@dataclass
class World:
    session: SandboxSession
    requests: list[SkillRequest] = field(default_factory=list)
    ended: ProgramEnded | None = None
    ended_after_s: float = 0.0


def drive(sessions: list[SandboxSession], sim_s: float = 0.0, motion_error: str | None = None) -> list[World]:
    """Run sessions to their ends the way the lockstep runner does; every session is closed after."""
    worlds = [World(s) for s in sessions]
    started = time.monotonic()
    for world in worlds:
        world.session.resume(None)
    pending = worlds
    try:
        while pending:
            moving = []
            for world in pending:
                message = world.session.wait()
                while isinstance(message, SkillRequest) and message.name in QUERIES:
                    world.requests.append(message)
                    world.session.resume(SkillReply(value=QUERY_VALUES[message.name]))
                    message = world.session.wait()
                if isinstance(message, ProgramEnded):
                    world.ended, world.ended_after_s = message, time.monotonic() - started
                else:
                    world.requests.append(message)
                    moving.append(world)
            time.sleep(sim_s)
            for world in moving:
                world.session.resume(SkillReply(error=motion_error))
            pending = moving
    finally:
        for world in worlds:
            world.session.close()
    return worlds


def motions(world: World) -> list[tuple[str, tuple[object, ...]]]:
    """The world's motion requests, positions rounded to the micrometre."""
    return [
        (r.name, tuple(tuple(round(v, 6) for v in a) if isinstance(a, tuple) else a for a in r.args))
        for r in world.requests
        if r.name not in QUERIES
    ]


def test_program_runs_through_the_protocol() -> None:
    (world,) = drive([SandboxSession(GRASP, "arm", FAST)])
    assert world.ended == ProgramEnded(error=None, output="grasp point [0.3, 0.0, 0.135]\n")
    assert motions(world) == GRASP_MOTIONS
    assert world.requests[0] == SkillRequest("get_graspable_point", ("milk",))


def test_helpers_lambdas_and_query_values_work_in_the_worker() -> None:
    code = (
        "import math\n"
        "def lift(p, dz=0.05):\n    return [p[0], p[1], p[2] + dz]\n"
        "box = get_workspace_range()\nsize = get_size('milk')\n"
        "top = min(box[2][1], 0.4)\n"
        "order = sorted([3, 1, 2], key=lambda v: -v)\n"
        "move_to_position(position=lift(get_center('milk'), dz=top - 0.1 * order[0]))\n"
        "print(round(math.hypot(size[0], size[1]), 4), order, sep=None, flush=True)\n"
    )
    (world,) = drive([SandboxSession(code, "arm", FAST)])
    assert world.ended == ProgramEnded(error=None, output="0.0622 [3, 2, 1]\n")
    assert motions(world) == [("move_to_position", ((0.3, 0.0, 0.2),))]


def test_array_methods_that_numpy_implements_in_python_work_in_the_worker() -> None:
    """numpy's C methods import their Python halves lazily through the program's ``__import__``."""
    code = (
        "import numpy as np\n"
        "a = np.array([1.0, 2.0, 3.5])\n"
        "print(a.mean(), a.std(), a.clip(0, 2).tolist(), a.round(0).tolist(), a.sum(axis=0), a.max(), a.prod())\n"
    )
    (world,) = drive([SandboxSession(code, "arm", FAST)])
    assert world.ended == ProgramEnded(
        error=None, output="2.1666666666666665 1.0274023338281628 [1.0, 2.0, 2.0] [1.0, 2.0, 4.0] 6.5 3.5 7.0\n"
    )


def test_named_unicode_escapes_compile_in_the_worker() -> None:
    """Compiling ``\\N{...}`` needs the unicodedata module, which the worker's empty root cannot load."""
    (world,) = drive([SandboxSession('print("90\\N{DEGREE SIGN}")\n', "arm", FAST)])
    assert world.ended == ProgramEnded(error=None, output="90\u00b0\n")


def test_motion_error_is_raised_inside_the_program_at_its_line() -> None:
    (world,) = drive([SandboxSession(GRASP, "arm", FAST)], motion_error="target outside the workspace")
    assert world.ended is not None
    assert world.ended.error == "line 4: SkillCallError: target outside the workspace"


def test_one_infinite_loop_in_sixteen_worlds_is_stopped_and_the_rest_finish() -> None:
    codes = [GRASP] * 16
    codes[5] = "open_gripper()\nwhile True:\n    pass\n"
    worlds = drive(start_sessions(codes, "arm", FAST))
    looping = worlds[5]
    assert looping.ended is not None and looping.ended.error == "CPU time limit exceeded (0.5 s)"
    assert motions(looping) == [("open_gripper", ())]
    assert looping.ended_after_s < 0.5 * 16 + 5  # its CPU budget, with all 16 worlds sharing two cores
    for i, world in enumerate(worlds):
        if i != 5:
            assert world.ended is not None and world.ended.error is None, (i, world.ended)
            assert motions(world) == GRASP_MOTIONS


def test_wall_clock_does_not_count_simulator_time() -> None:
    limits = FAST.model_copy(update={"wall_s": 1.0})
    (world,) = drive([SandboxSession(GRASP, "arm", limits)], sim_s=0.4)  # 4 motions: 1.6 s simulated
    assert world.ended is not None and world.ended.error is None


def test_wall_clock_stops_a_program_that_overruns_it() -> None:
    limits = FAST.model_copy(update={"cpu_s": 30.0, "wall_s": 0.5})
    started = time.monotonic()
    (world,) = drive([SandboxSession("x = 0\nwhile True:\n    x += 1\n", "arm", limits)])
    assert world.ended is not None
    assert world.ended.error == "wall-clock limit exceeded (0.5 s of program time)"
    assert time.monotonic() - started < 3.0


@pytest.mark.slow
def test_a_program_is_not_charged_for_the_time_the_runner_waits_on_others() -> None:
    """Found by an adversarial run: the runner waited on the worlds in turn, and a good program whose reply sat unread
    behind busy-looping ones was charged for them: it ran out of its wall-clock budget at its next call. Waited on as
    their messages arrive (:func:`~robotool.program_session.wait_all`), each world pays for its own time only."""
    limits = FAST.model_copy(update={"cpu_s": 1.0, "wall_s": 1.5})
    sessions = start_sessions(
        ["x = 0\nwhile True:\n    x += 1\n"] * 4 + ["open_gripper()\nclose_gripper()\n"], "arm", limits
    )
    try:
        for session in sessions:
            session.resume(None)
        started = time.monotonic()
        *spinning, good = wait_all(sessions)
        assert time.monotonic() - started > 1.5  # the good world's reply waited behind theirs, longer than its budget
        assert all(isinstance(m, ProgramEnded) and m.error for m in spinning), spinning
        assert good == SkillRequest("open_gripper", ())
        sessions[-1].resume(SkillReply())
        assert wait_all(sessions[-1:]) == [SkillRequest("close_gripper", ())]
    finally:
        for session in sessions:
            session.close()


def test_crashed_worker_fails_only_its_world() -> None:
    sessions = start_sessions([GRASP] * 3, "arm", FAST)
    for s in sessions:
        s.resume(None)
    first = [s.wait() for s in sessions]
    assert all(isinstance(m, SkillRequest) for m in first)
    assert sessions[1].worker_pid is not None
    os.kill(sessions[1].worker_pid, signal.SIGSEGV)
    sessions[1].resume(SkillReply(value=QUERY_VALUES["get_graspable_point"]))
    assert sessions[1].wait() == ProgramEnded(error="the worker crashed (SIGSEGV)")
    for s in (sessions[0], sessions[2]):
        s.resume(SkillReply(value=QUERY_VALUES["get_graspable_point"]))
    worlds = drive_on([sessions[0], sessions[2]])
    assert all(w.ended is not None and w.ended.error is None for w in worlds)


def drive_on(sessions: list[SandboxSession]) -> list[World]:
    """Finish started sessions whose next message is pending (answering motions at once)."""
    worlds = [World(s) for s in sessions]
    for world in worlds:
        message = world.session.wait()
        while isinstance(message, SkillRequest):
            world.requests.append(message)
            world.session.resume(SkillReply(value=QUERY_VALUES.get(message.name)))
            message = world.session.wait()
        world.ended = message
        world.session.close()
    return worlds


def test_close_kills_a_running_worker() -> None:
    session = SandboxSession("while True:\n    pass\n", "arm", FAST.model_copy(update={"cpu_s": 60.0}))
    session.resume(None)
    pid = session.worker_pid
    assert pid is not None and Path(f"/proc/{pid}").exists()
    session.close()
    assert session.wait() == ProgramEnded(error="closed before the program ended")
    deadline = time.monotonic() + 2
    while Path(f"/proc/{pid}").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not Path(f"/proc/{pid}").exists()


def test_rejected_program_gets_no_worker_and_ends_with_the_reason() -> None:
    session = SandboxSession("import os\n", "arm")
    assert session.worker_pid is None
    session.resume(None)
    reason = "import of 'os' is not allowed; only `import numpy as np` and `import math`"
    assert session.wait() == ProgramEnded(error=f"program rejected: line 1: {reason}")


def test_resume_must_start_with_none_then_take_replies() -> None:
    session = SandboxSession(GRASP, "arm", FAST)
    try:
        with pytest.raises(ValueError, match="starts the program"):
            session.resume(SkillReply(value=1))
        session.resume(None)
        assert isinstance(session.wait(), SkillRequest)
        with pytest.raises(ValueError, match="starts the program"):
            session.resume(None)
    finally:
        session.close()


def _expectation(path: Path) -> tuple[str, str]:
    """The corpus file's first line: ``# expect rejected|stopped: <words in the reason>``."""
    header = path.read_text().splitlines()[0]
    kind, words = header.removeprefix("# expect ").split(": ", 1)
    return kind, words


@pytest.fixture(scope="module")
def hostile_batch() -> dict[str, World]:
    """Every corpus program that passes validation, in one batch with two well-behaved programs."""
    stopped = [p for p in HOSTILE if _expectation(p)[0] == "stopped"]
    codes = [GRASP, *(p.read_text() for p in stopped), GRASP]
    zygote().layers()  # started before counting: its control socket stays open
    fds_before = len(os.listdir("/proc/self/fd"))
    worlds = drive(start_sessions(codes, "arm", FAST))
    assert len(os.listdir("/proc/self/fd")) == fds_before
    named = {p.stem: w for p, w in zip(stopped, worlds[1:-1], strict=True)}
    return {"first_good": worlds[0], "last_good": worlds[-1], **named}


def test_corpus_is_large_enough() -> None:
    assert len(HOSTILE) >= 30
    assert {_expectation(p)[0] for p in HOSTILE} == {"rejected", "stopped"}


@pytest.mark.parametrize("path", HOSTILE, ids=lambda p: p.stem)
def test_hostile_program_is_refused_or_stopped(path: Path, hostile_batch: dict[str, World]) -> None:
    kind, words = _expectation(path)
    if kind == "rejected":
        with pytest.raises(ProgramRejected) as caught:
            validate(path.read_text(), "arm")
        assert words in str(caught.value)
        assert caught.value.line is not None and caught.value.line >= 2  # the header is line 1
        return
    validate(path.read_text(), "arm")
    ended = hostile_batch[path.stem].ended
    assert ended is not None and ended.error is not None and words in ended.error


def test_hostile_batch_leaves_host_and_good_worlds_unaffected(hostile_batch: dict[str, World]) -> None:
    for name in ("first_good", "last_good"):
        world = hostile_batch[name]
        assert world.ended == ProgramEnded(error=None, output="grasp point [0.3, 0.0, 0.135]\n")
        assert motions(world) == GRASP_MOTIONS
    assert not CANARY.exists()
    assert len(hostile_batch["huge_print_loop"].ended.output) <= FAST.max_output_chars  # type: ignore[union-attr]


def test_worker_namespace_has_only_allowlisted_modules() -> None:
    """Defence in depth: were the validator bypassed, the dangerous names still would not exist."""
    from robotool.sandbox.worker import _import

    numpy_view = _import("numpy")
    assert hasattr(numpy_view, "array") and hasattr(numpy_view.linalg, "norm")
    assert not any(hasattr(numpy_view, n) for n in ("load", "save", "fromfile", "memmap", "ctypeslib", "lib"))
    for name, fromlist in (("os", ()), ("numpy", ("load",)), ("numpy.ctypeslib", ())):
        with pytest.raises(ImportError):
            _import(name, None, None, fromlist)


def test_zygote_does_not_inherit_the_host_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROBOTOOL_TEST_API_KEY", "sk-secret")
    fresh = Zygote()
    try:
        (worker,) = fresh.spawn(1)
        worker_pid = worker.host_pid
        for pid in (fresh.process.pid, worker_pid):
            environment = Path(f"/proc/{pid}/environ").read_bytes()
            assert b"sk-secret" not in environment and b"OPENBLAS_NUM_THREADS=1" in environment
    finally:
        fresh.close()
    assert not Path(f"/proc/{worker_pid}").exists()
