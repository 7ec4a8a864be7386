"""The operating-system boundary: what a worker cannot do even with the Python-level checks switched off.

These programs run through ``SandboxSession(..., test_only_skip_python_checks=True)``: no validator,
every builtin, ``import os`` works. Only the OS layers (seccomp filter, namespaces, empty root,
unprivileged uid, rlimits) stand between them and the host.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from fixtures.paths import FIXTURES
from fixtures.sandbox_driver import run_to_end

from robotool.program_session import ProgramEnded, SkillReply, SkillRequest
from robotool.sandbox import SandboxLimits, SandboxSession, layers_in_use, start_sessions
from robotool.sandbox.allowlist import NUMPY_FUNCTIONS, NUMPY_LINALG
from robotool.sandbox.zygote import Zygote, zygote

ESCAPES = FIXTURES / "escapes"
LIMITS = SandboxLimits(cpu_s=2.0, wall_s=20.0, memory_mb=128, max_output_chars=20_000, max_skill_calls=50)


def run_unchecked(code: str, limits: SandboxLimits = LIMITS) -> ProgramEnded:
    """Run ``code`` without the Python-level checks; skill calls are answered with a fixed point."""
    return run_to_end(code, limits, unchecked=True)


def test_every_layer_is_in_force_on_this_machine() -> None:
    zygote().spawn(1)[0].conn.close()
    layers = layers_in_use()
    assert layers is not None and layers.seccomp and layers.warning() is None
    for layer in ("PID namespace", "network namespace", "IPC namespace", "mount namespace", "empty root"):
        assert layer in layers.in_force, layers.summary()
    if os.geteuid() == 0:
        assert "uid nobody" in layers.in_force


def test_os_calls_are_denied_without_the_python_checks() -> None:
    """open, create, socket, /proc/<ppid>/environ, kill, fork, exec, setsid, memfd, pidfd, setuid, mkfifo,
    switching off the CPU timer's signal: each fails with EPERM."""
    canary = Path("/tmp/robotool-escape-canary")
    canary.unlink(missing_ok=True)
    ended = run_unchecked((ESCAPES / "os_calls.py").read_text())
    assert ended.error is None, ended.error
    outcomes = dict(line.rsplit(" ", 2)[:2] for line in ended.output.splitlines())
    assert len(outcomes) == 21
    assert all(outcome == "denied" for outcome in outcomes.values()), ended.output
    assert all(line.endswith(" 1") for line in ended.output.splitlines())  # EPERM: the seccomp filter
    assert not canary.exists()
    assert zygote().alive()


def test_a_program_cannot_signal_the_host_or_a_sibling() -> None:
    """Two workers: one tries every PID it might guess for the host, the zygote and its sibling."""
    victim = SandboxSession("move_to_position([0.3, 0.0, 0.2])\n", "arm", LIMITS)
    victim.resume(None)
    assert isinstance(victim.wait(), SkillRequest)
    guesses = [os.getpid(), victim.worker_pid, 1, 2, 3, 4]
    code = (
        "import os\nhits = []\n"
        f"for pid in {guesses}:\n"
        "    try:\n        os.kill(pid, 9)\n        hits.append(pid)\n    except OSError:\n        pass\n"
        "print(hits)\n"
    )
    try:
        assert run_unchecked(code).output == "[]\n"
        victim.resume(SkillReply(value=None))
        assert victim.wait() == ProgramEnded(error=None)
    finally:
        victim.close()


def test_no_process_outlives_its_zygote() -> None:
    """A worker that tries to leave a process behind leaves none: fork is denied, and what is left in
    the PID namespace when the zygote ends is killed by the kernel."""
    fresh = Zygote()
    try:
        (worker,) = fresh.spawn(1)
        code = "import os\ntry:\n    os.fork()\nexcept OSError as e:\n    print(e.errno)\nwhile True:\n    pass\n"
        session = SandboxSession(code, "arm", LIMITS, worker=worker, test_only_skip_python_checks=True)
        session.resume(None)
        time.sleep(0.5)
        zygote_pids = _descendants(fresh.process.pid)
        assert worker.host_pid in zygote_pids
        assert _descendants(worker.host_pid) == {worker.host_pid}  # its fork was denied
    finally:
        fresh.close()
    deadline = time.monotonic() + 5
    while any(Path(f"/proc/{pid}").exists() for pid in zygote_pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [pid for pid in zygote_pids if Path(f"/proc/{pid}").exists()]


def _descendants(pid: int) -> set[int]:
    found, todo = set(), [pid]
    while todo:
        current = todo.pop()
        found.add(current)
        for task in Path(f"/proc/{current}/task").iterdir():
            todo += [int(p) for p in (task / "children").read_text().split()]
    return found


def test_workers_share_no_writable_memory_and_have_no_writable_code() -> None:
    """Workers are forks of one zygote: a shared writable mapping would be a channel between programs
    (and to the zygote), and a writable executable one a place for machine code."""
    workers = zygote().spawn(2)
    try:
        for worker in workers:
            try:
                maps = Path(f"/proc/{worker.host_pid}/maps").read_text().splitlines()
            except PermissionError:
                pytest.skip("a non-dumpable worker's memory map is readable only by root")
            flags = [line.split()[1] for line in maps]
            assert flags and not [f for f in flags if "w" in f and ("s" in f or "x" in f)], maps
    finally:
        for worker in workers:
            worker.conn.close()
            worker.zygote.release(worker.pid)


def test_crash_inside_native_code_fails_only_its_world() -> None:
    crash = "import ctypes\nctypes.string_at(0)\n"
    ended = run_unchecked(crash)
    assert ended.error == "the worker crashed (SIGSEGV)"


def test_memory_and_cpu_limits_hold_without_the_python_checks() -> None:
    assert run_unchecked("x = bytearray(512 * 2**20)\n").error == "memory limit exceeded (128 MiB)"
    spin = run_unchecked("while True:\n    pass\n", LIMITS.model_copy(update={"cpu_s": 0.3}))
    assert spin.error == "CPU time limit exceeded (0.3 s)"


def test_a_batch_shares_one_memory_budget() -> None:
    """Each of a batch's N programs may add ``batch_memory_mb / N``: with only the per-program limit, 256
    default workers (256 MiB each) could hold 64 GiB at once, more than most hosts have."""
    limits = LIMITS.model_copy(update={"memory_mb": 256, "batch_memory_mb": 64})
    fits, too_big = "x = b'x' * 12 * 2**20\nprint(len(x) // 2**20)\n", "x = b'x' * 20 * 2**20\n"
    sessions = start_sessions([fits, too_big, fits, too_big], "arm", limits)
    ended = []
    for session in sessions:
        session.resume(None)
        ended.append(session.wait())
        session.close()
    share = ProgramEnded(error="memory limit exceeded (16 MiB)")
    assert ended == [ProgramEnded(error=None, output="12\n"), share, ProgramEnded(error=None, output="12\n"), share]
    alone = run_unchecked(too_big, limits.model_copy(update={"batch_memory_mb": 8}))
    assert alone.error == "memory limit exceeded (8 MiB)"  # one program never gets more than the batch


def test_all_workers_of_a_zygote_share_its_memory_cgroup() -> None:
    """Batches that run at once each keep to their own budget; the memory cgroup bounds them together:
    two workers allowed 256 MiB each by their limits cannot hold 2 x 64 MiB under a 96 MiB zygote."""
    fresh = Zygote(memory_mb=96)
    try:
        (first, second) = fresh.spawn(2)
        layers = fresh.layers()
        if "memory cgroup" not in layers.in_force:
            pytest.skip(f"no memory cgroup here: {layers.missing['memory cgroup']}")
        limits = LIMITS.model_copy(update={"memory_mb": 256, "batch_memory_mb": 1024})
        code = "x = b'x' * 64 * 2**20\nget_center('milk')\nprint(len(x) // 2**20)\n"
        sessions = [SandboxSession(code, "arm", limits, worker=w) for w in (first, second)]
        for session in sessions:
            session.resume(None)
        first_messages = [session.wait() for session in sessions]  # both allocated, or killed, by now
        ended = [_finish(session, message) for session, message in zip(sessions, first_messages, strict=True)]
        assert sorted(e.error or "" for e in ended) == ["", "the worker was killed (out of memory?)"], ended
        assert fresh.alive()
    finally:
        fresh.close()


def _finish(session: SandboxSession, message: SkillRequest | ProgramEnded) -> ProgramEnded:
    """Run a session from its last message to its end, answering skills with a point."""
    while isinstance(message, SkillRequest):
        session.resume(SkillReply(value=[0.3, 0.0, 0.1]))
        message = session.wait()
    session.close()
    return message


def test_the_default_batch_memory_fits_the_machine() -> None:
    physical_mb = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2**20
    for programs in (1, 16, 256, 4096):
        assert SandboxLimits().for_batch(programs).memory_mb * programs <= physical_mb // 2
    assert SandboxLimits().for_batch(1).memory_mb == 256
    with pytest.raises(ValueError, match="a batch of 100 programs does not fit in 64 MiB"):
        SandboxLimits(batch_memory_mb=64).for_batch(100)


def test_worker_stderr_never_reaches_the_host(capfd: pytest.CaptureFixture[str]) -> None:
    recursion = f"def {'f' * 5000}(n):\n    return {'f' * 5000}(n + 1)\n{'f' * 5000}(0)\n"
    assert run_unchecked(recursion).error == "line 2: RecursionError: maximum recursion depth exceeded"
    writes = run_unchecked("import os, sys\nsys.stderr.write('x' * 100000)\nsys.stderr.flush()\n")
    assert writes.error == "line 2: PermissionError: [Errno 1] Operation not permitted"
    assert capfd.readouterr().err == ""


def test_every_allowlisted_numpy_function_works_inside_the_jail() -> None:
    """The worker's root is empty: a numpy function that imports lazily would fail there."""
    calls = {
        "arange": "(3)",
        "linspace": "(0, 1, 3)",
        "eye": "(2)",
        "identity": "(2)",
        "zeros": "(2)",
        "ones": "(2)",
        "full": "(2, 1.5)",
        "meshgrid": "(v, v)",
        "interp": "(0.5, [0, 1], [0, 2])",
        "einsum": "('ij,jk->ik', m, m)",
        "arctan2": "(1.0, 2.0)",
        "hypot": "(3.0, 4.0)",
        "power": "(v, 2)",
        "minimum": "(v, 1)",
        "maximum": "(v, 1)",
        "where": "(v > 1, v, 0)",
        "clip": "(v, 0, 1)",
        "cross": "(v, v)",
        "dot": "(v, v)",
        "inner": "(v, v)",
        "full_like": "(v, 2.0)",
        "outer": "(v, v)",
        "matmul": "(m, m)",
        "allclose": "(v, v)",
        "isclose": "(v, v)",
        "mod": "(v, 2)",
        "fmod": "(v, 2)",
        "remainder": "(v, 2)",
        "floor_divide": "(v, 2)",
        "append": "(v, 1)",
        "repeat": "(v, 2)",
        "tile": "(v, 2)",
        "roll": "(v, 1)",
        "reshape": "(v, (3, 1))",
        "expand_dims": "(v, 0)",
        "stack": "([v, v])",
        "vstack": "([v, v])",
        "hstack": "([v, v])",
        "concatenate": "([v, v])",
        "column_stack": "([v, v])",
    }
    linalg = {"solve": "(m, [1.0, 2.0])", "lstsq": "(m, [1.0, 2.0], rcond=None)"}
    lines = ["import numpy as np", "v = np.array([1.0, 2.0, 3.0])", "m = np.array([[2.0, 1.0], [1.0, 3.0]])"]
    lines += [f"print('{n}', np.{n}{calls.get(n, '(v)')} is not None)" for n in sorted(NUMPY_FUNCTIONS)]
    lines += [f"print('linalg.{n}', np.linalg.{n}{linalg.get(n, '(m)')} is not None)" for n in sorted(NUMPY_LINALG)]
    ended = run_unchecked("\n".join(lines) + "\n")
    assert ended.error is None, ended.error
    worked = {line.removesuffix(" True") for line in ended.output.splitlines() if line.endswith(" True")}
    assert worked == NUMPY_FUNCTIONS | {f"linalg.{n}" for n in NUMPY_LINALG}


def test_a_killed_worker_group_takes_what_it_left() -> None:
    """Closing a session kills the worker's whole process group, not just the worker."""
    session = SandboxSession("while True:\n    pass\n", "arm", LIMITS.model_copy(update={"cpu_s": 60.0}))
    session.resume(None)
    pid = session.worker_pid
    assert pid is not None and os.getpgid(pid) == pid
    session.close()
    deadline = time.monotonic() + 2
    while Path(f"/proc/{pid}").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not Path(f"/proc/{pid}").exists()
    with pytest.raises(ProcessLookupError):
        os.killpg(pid, 0)


def test_batch_of_unchecked_programs_leaves_good_worlds_alone() -> None:
    hostile = (ESCAPES / "os_calls.py").read_text()
    good = "move_to_position([0.3, 0.0, 0.2])\nprint('ok')\n"
    sessions = start_sessions([good, good], "arm", LIMITS)
    bad = run_unchecked(hostile)
    assert "achieved" not in bad.output
    for s in sessions:
        s.resume(None)
        assert isinstance(s.wait(), SkillRequest)
        s.resume(SkillReply(value=None))
        assert s.wait() == ProgramEnded(error=None, output="ok\n")
        s.close()


def test_raw_system_calls_from_native_code_are_denied() -> None:
    """ctypes reaches libc.syscall directly: fork, clone, kill, ptrace, switching off the CPU timer,
    raising rlimits, adding filters, new namespaces and executable memory all fail with EPERM."""
    ended = run_unchecked((ESCAPES / "native_code.py").read_text())
    assert ended.error is None, ended.error
    lines = ended.output.splitlines()
    assert len(lines) == 10 and all(line.endswith(" denied 1") for line in lines), ended.output


def test_kernel_interfaces_to_other_processes_and_descriptors_are_denied() -> None:
    """ptrace, process_vm_readv/writev, userfaultfd, io_uring, bpf, perf events, keyrings, mount, setns,
    clone3, personality, prctl, TIOCSTI, openat2, file handles, SCM_RIGHTS, executable or shared memory,
    execveat, getdents, dup/close of the host socket, rlimits, signals to other processes, module loading:
    each fails with EPERM (mapping the socket is refused by the kernel itself, ENODEV)."""
    ended = run_unchecked((ESCAPES / "kernel_surfaces.py").read_text())
    assert ended.error is None, ended.error
    outcomes = dict(line.rsplit(" ", 1) for line in ended.output.splitlines())
    assert len(outcomes) == 50
    assert outcomes.pop("mmap socket denied") == "19"
    assert set(outcomes.values()) == {"1"} and all(o.endswith(" denied") for o in outcomes), ended.output


def test_namespaces_clocks_devices_and_other_processes_are_denied() -> None:
    """A new user namespace, fork, the host's clocks, name and swap, device nodes and links, System V IPC, another
    process's limits and signals, and terminal ioctls on stdout: each fails with EPERM, from the filter."""
    ended = run_unchecked((ESCAPES / "namespaces_clocks_and_devices.py").read_text())
    assert ended.error is None, ended.error
    outcomes = dict(line.rsplit(" ", 1) for line in ended.output.splitlines())
    assert len(outcomes) == 24
    assert set(outcomes.values()) == {"1"} and all(o.endswith(" denied") for o in outcomes), ended.output


def test_allowed_system_calls_refuse_the_arguments_a_worker_never_needs() -> None:
    """futex and madvise are allowed, but not their priority-inheritance and requeue operations, shared
    futexes, page merging across processes, page-out or poisoning; executable memory stays refused however
    the protection is spelt, and a denied call stays denied however its number is spelt. Each fails with
    EPERM, from the filter."""
    ended = run_unchecked((ESCAPES / "allowed_call_arguments.py").read_text())
    assert ended.error is None, ended.error
    lines = ended.output.splitlines()
    assert len(lines) == 24 and all(line.endswith(" denied 1") for line in lines), ended.output


def test_scheduling_kernel_state_and_new_descriptor_kinds_are_denied() -> None:
    """Real-time scheduling (which would starve the host), I/O priority, kcmp, other processes' robust lists
    and pages, memory policy, the kernel log, mincore, the LDT, timer/event/signal/notify descriptors, the new
    mount API, landlock, futex2, rseq, close_range, accounting, kexec, signal actions: each fails with EPERM."""
    ended = run_unchecked((ESCAPES / "scheduling_and_kernel_state.py").read_text())
    assert ended.error is None, ended.error
    lines = ended.output.splitlines()
    assert len(lines) == 34 and all(line.endswith(" denied 1") for line in lines), ended.output


def test_a_worker_holds_no_descriptor_but_its_standard_streams_and_socket() -> None:
    """/proc/self/fd cannot be listed in the empty root, but mmap (allowed) tells a closed descriptor (EBADF)
    from an open one: nothing the host or the zygote had open is left to the program."""
    code = (
        "import ctypes\nlibc = ctypes.CDLL(None, use_errno=True)\nlibc.mmap.restype = ctypes.c_void_p\n"
        "c = ctypes\nlibc.mmap.argtypes = [c.c_void_p, c.c_size_t, c.c_int, c.c_int, c.c_int, c.c_long]\n"
        "failed = ctypes.c_void_p(-1).value\n"
        "print([fd for fd in range(4096) if libc.mmap(None, 4096, 1, 2, fd, 0) != failed or ctypes.get_errno() != 9])\n"
    )
    assert run_unchecked(code).output == "[0, 1, 2, 3]\n"


def test_system_calls_through_a_foreign_abi_kill_the_worker() -> None:
    ended = run_unchecked((ESCAPES / "x32_abi.py").read_text())
    assert ended.error == "the worker was stopped by the sandbox's system-call filter (SIGSYS)"


def test_machine_code_cannot_be_placed_in_executable_memory() -> None:
    """Jumping into hand-written i386 code fails before the kernel sees it: no page is executable."""
    assert run_unchecked((ESCAPES / "i386_abi.py").read_text()).error == "the worker crashed (SIGSEGV)"


def test_a_worker_still_dies_with_its_zygote_after_dropping_its_uid() -> None:
    """Changing credentials clears the parent-death signal; the jail sets it again afterwards. It
    also leaves the worker no capability."""
    import ctypes

    from robotool.sandbox.jail import WorkerJail

    worker_jail = WorkerJail()
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            status = os.open("/proc/self/status", os.O_RDONLY)  # opened before the root is emptied
            worker_jail.enter()
            effective = next(line for line in os.read(status, 4096).decode().splitlines() if line.startswith("CapEff"))
            signal_number = ctypes.c_int(0)
            ctypes.CDLL(None).prctl(2, ctypes.byref(signal_number), 0, 0, 0)  # PR_GET_PDEATHSIG
            os.write(write_end, bytes([signal_number.value, os.getuid() != 0, int(effective.split()[1], 16) == 0]))
        finally:
            os._exit(0)
    os.close(write_end)
    reply = os.read(read_end, 3)
    os.waitpid(pid, 0)
    os.close(read_end)
    assert reply == bytes([9, os.geteuid() == 0, 1])


def test_the_program_text_is_compiled_only_under_the_seccomp_filter() -> None:
    """Compiling hostile text is the first thing that reads it: were the compiler crashable into running
    code, that code must already be filtered. A worker with a jail double reports when it compiled."""
    import socket
    from multiprocessing.connection import Connection

    from robotool import robots
    from robotool.sandbox import worker
    from robotool.sandbox.messages import GO, WorkerMessage, encode_start

    class RecordingJail:
        sealed = False

        def enter(self) -> None:
            pass

        def seal(self) -> None:
            self.sealed = True

    host_end, worker_end = socket.socketpair()
    pid = os.fork()
    if pid == 0:
        try:
            jail = RecordingJail()
            real_compile = compile
            worker.compile = lambda *args: real_compile(*args) if jail.sealed else SyntaxError("compiled unfiltered")
            worker.serve(worker_end.fileno(), jail)  # type: ignore[arg-type]
        finally:
            os._exit(1)
    worker_end.close()
    host = Connection(host_end.detach())
    try:
        host.send_bytes(encode_start("x = 1\n", robots.get("arm").skills, LIMITS, python_checks=True))
        host.send_bytes(GO)
        ended = WorkerMessage.model_validate_json(host.recv_bytes())
    finally:
        host.close()
        os.waitpid(pid, 0)
    assert ended.error is None


def test_a_machine_without_seccomp_is_told_loudly(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without libseccomp the probe reports the filter missing, and the reports warn in red."""
    from io import StringIO

    from rich.console import Console

    from robotool.cli import summary
    from robotool.sandbox import SandboxWarning, jail

    monkeypatch.setattr(jail, "_syscall_filter", lambda: (None, "pyseccomp/libseccomp unavailable: test"))
    layers = jail.WorkerJail().probe(["PID"], {}, None)
    assert not layers.seccomp and layers.missing["seccomp filter"] == "pyseccomp/libseccomp unavailable: test"
    with pytest.warns(SandboxWarning, match="WITHOUT the seccomp filter"):
        jail.warn_if_weak(layers)
    monkeypatch.setattr(summary, "layers_in_use", lambda: layers)
    console = Console(file=StringIO(), width=200)
    summary.print_sandbox_layers(console)
    shown = console.file.getvalue()  # type: ignore[attr-defined]
    assert "sandbox: PID namespace" in shown and "missing: " in shown and "WARNING: generated programs" in shown


def test_nothing_outlives_a_host_killed_mid_run() -> None:
    """SIGKILL the host while its workers spin: the zygote and every worker die with it."""
    import subprocess
    import sys

    script = (
        "import sys, time\n"
        "from robotool.sandbox import SandboxLimits, start_sessions\n"
        "from robotool.sandbox.zygote import zygote\n"
        "sessions = start_sessions(['while True:\\n    pass\\n'] * 2, 'arm', SandboxLimits(cpu_s=60.0, wall_s=60.0))\n"
        "for s in sessions:\n    s.resume(None)\n"
        "print(zygote().process.pid, *(s.worker_pid for s in sessions), flush=True)\n"
        "time.sleep(60)\n"
    )
    host = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert host.stdout is not None
        pids = [int(p) for p in host.stdout.readline().split()]
        tree = set().union(*(_descendants(pid) for pid in pids[:1]))
        assert set(pids) <= tree
    finally:
        host.kill()
        host.wait()
    deadline = time.monotonic() + 5
    while any(Path(f"/proc/{pid}").exists() for pid in tree) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [pid for pid in tree if Path(f"/proc/{pid}").exists()]


def test_a_program_cannot_raise_its_limits_start_threads_or_reprioritise_the_host() -> None:
    """Raising the CPU, memory or process limits, a higher priority, lowering the parent's, a thread, a signal to
    the parent's process group: each is denied (EPERM from the filter; a thread cannot start)."""
    ended = run_unchecked((ESCAPES / "limits_and_threads.py").read_text())
    assert ended.error is None, ended.error
    outcomes = [line.rsplit(" ", 2) for line in ended.output.splitlines()]
    assert len(outcomes) == 7
    assert all(outcome == "denied" for _, outcome, _ in outcomes), ended.output
    assert zygote().alive()


def test_the_hosts_name_clocks_and_ipc_are_out_of_reach() -> None:
    """Setting the host's name or the system clocks, System V and POSIX IPC objects (which a worker could share with
    another), device nodes, swap and quotas: each fails with EPERM, from the filter."""
    ended = run_unchecked((ESCAPES / "host_identity_clocks_and_ipc.py").read_text())
    assert ended.error is None, ended.error
    lines = ended.output.splitlines()
    assert len(lines) == 14 and all(line.endswith(" denied 1") for line in lines), ended.output


def test_signals_new_sessions_forks_init_and_the_terminal_are_out_of_reach() -> None:
    """With the Python checks off: signals to the parent, the process group and init, a new session, a fork,
    init's /proc entry and the controlling terminal are all refused by the OS layers (errno 1, EPERM)."""
    code = (
        "import ctypes, os\n"
        "libc = ctypes.CDLL(None, use_errno=True)\n"
        "out = []\n"
        "for name, call in [('parent', lambda: libc.kill(libc.getppid(), 0)), ('group', lambda: libc.kill(0, 0)),\n"
        "                   ('init', lambda: libc.kill(1, 15)), ('setsid', libc.setsid), ('fork', libc.fork)]:\n"
        "    out.append((name, call(), ctypes.get_errno()))\n"
        "for path, flags in [('/proc/1/cmdline', os.O_RDONLY), ('/dev/tty', os.O_WRONLY)]:\n"
        "    try:\n"
        "        os.open(path, flags)\n"
        "        out.append((path, 'opened'))\n"
        "    except OSError as e:\n"
        "        out.append((path, e.errno))\n"
        "print(out)\n"
    )
    ended = run_unchecked(code)
    assert ended.output == (
        "[('parent', -1, 1), ('group', -1, 1), ('init', -1, 1), ('setsid', -1, 1), ('fork', -1, 1), "
        "('/proc/1/cmdline', 1), ('/dev/tty', 1)]\n"
    ), ended.output
