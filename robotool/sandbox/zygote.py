"""The zygote: a fresh interpreter, numpy and the worker preloaded, that forks one worker per program.

Why not ``multiprocessing``: a ``spawn`` worker pays a fresh interpreter and numpy import (~100 ms)
per program, which is seconds for a 256-world batch on two cores; ``fork`` from the host would copy
the simulator, its threads and its GPU context into untrusted code. Its ``forkserver`` has the
right shape but re-imports the host's ``__main__`` (a benchmark script that imports the simulator,
or pytest) in every worker and exchanges pickles. So this module is the forkserver pattern, direct:
the host starts the zygote (:func:`main`) in a new interpreter once, and each worker is an
``os.fork`` of it (about a millisecond) with its own socket to the host.

The zygote sets up the operating-system layers (:mod:`robotool.sandbox.jail`) when it starts: it
enters new namespaces, and when one of them is a PID namespace it forks once more, so that the
server is that namespace's init and the kernel kills every process left in it when the server ends.
It probes which layers hold and reports them to the host on request (:meth:`Zygote.layers`).

Start-up is kept off the host's critical path: the zygote forks a batch in one request, and while
idle it pre-forks as many spare workers (blocked, waiting for a program) as the last batch asked
for, so the next batch of that size is handed out without forking.

The zygote is the workers' parent, so it alone kills and reaps them: no PID can be reused under a
kill. Each worker leads its own process group, and a kill takes the whole group. Host and zygote
talk over a ``SOCK_SEQPACKET`` socket in JSON requests; ``spawn``, ``status``, ``layers`` and
``host_pid`` are answered, and the host reads each answer right away, so neither side can block
the other. When the host goes away the zygote kills its workers and exits.
"""

from __future__ import annotations

import contextlib
import gc
import json
import os
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from multiprocessing.connection import Connection
from pathlib import Path
from typing import NamedTuple

from robotool.sandbox import jail, worker
from robotool.sandbox.limits import default_batch_memory_mb

MAX_SPARES = 256
"""Most idle workers the zygote keeps ready."""

_INHERITED_ENV = ("PATH", "LANG", "LC_ALL", "LD_LIBRARY_PATH", "TMPDIR")
_REPLY_TIMEOUT_S = 60.0
_EXIT_GRACE_S = 2.0


class ZygoteError(RuntimeError):
    """The zygote process could not be started or stopped answering."""


class Worker(NamedTuple):
    """A forked worker: its PID in the zygote's namespace, the host's end of its socket, and the
    zygote that owns it."""

    pid: int
    conn: Connection
    zygote: Zygote

    @property
    def host_pid(self) -> int:
        """The worker's PID as this process sees it (asked of the zygote: it differs in a PID namespace)."""
        return self.zygote.host_pid(self.pid)


class Zygote:
    """Host-side handle on the zygote process, whose workers together may hold at most ``memory_mb`` MiB
    (default: :func:`~robotool.sandbox.limits.default_batch_memory_mb`) where a memory cgroup is available."""

    def __init__(self, memory_mb: int | None = None) -> None:
        self._control, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._control.settimeout(_REPLY_TIMEOUT_S)
        package_root = str(Path(__file__).resolve().parents[2])
        # Only what the interpreter needs: API keys and the like in the host's environment stay there.
        env = {k: os.environ[k] for k in _INHERITED_ENV if k in os.environ}
        env.update(
            PYTHONPATH=os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")])),
            # One BLAS thread: a forked worker cannot use a thread pool, and the buffers cost address space.
            OPENBLAS_NUM_THREADS="1",
            OMP_NUM_THREADS="1",
            MKL_NUM_THREADS="1",
        )
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-c",
                "from robotool.sandbox.zygote import main; main()",
                str(theirs.fileno()),
                str(memory_mb or default_batch_memory_mb()),
            ],
            pass_fds=[theirs.fileno()],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            env=env,
        )
        theirs.close()
        self._lock = threading.Lock()
        self._layers: jail.SandboxLayers | None = None

    def spawn(self, count: int) -> list[Worker]:
        """``count`` fresh workers, each waiting for its program."""
        self.layers()  # learnt once, before the first worker: warns when seccomp is missing
        with self._lock:
            self._send({"op": "spawn", "count": count})
            workers = []
            for _ in range(count):
                data, fds = self._receive(with_fd=True)
                workers.append(Worker(json.loads(data)["pid"], Connection(fds[0]), self))
            return workers

    def host_pid(self, pid: int) -> int:
        """A running worker's PID as this process sees it."""
        with self._lock:
            self._send({"op": "host_pid", "pid": pid})
            data, _ = self._receive(with_fd=False)
            return int(json.loads(data)["host_pid"])

    def layers(self) -> jail.SandboxLayers:
        """The OS layers the zygote's workers run under (asked once; warns when seccomp is missing)."""
        with self._lock:
            if self._layers is None:
                self._send({"op": "layers"})
                data, _ = self._receive(with_fd=False)
                self._layers = jail.SandboxLayers.model_validate_json(data)
                jail.warn_if_weak(self._layers)
            return self._layers

    def exit_code(self, pid: int) -> int:
        """How a worker that closed its socket ended (negative: killed by that signal)."""
        with self._lock:
            self._send({"op": "status", "pid": pid})
            data, _ = self._receive(with_fd=False)
            return int(json.loads(data)["code"])

    def release(self, pid: int) -> None:
        """Kill the worker if it still runs and forget it; not answered."""
        with self._lock:
            self._send({"op": "release", "pid": pid})

    def alive(self) -> bool:
        return self.process.poll() is None

    def close(self) -> None:
        """Stop the zygote; it kills its workers on the way out."""
        self._control.close()
        self.process.wait()

    def _send(self, request: dict[str, object]) -> None:
        try:
            self._control.send(json.dumps(request).encode())
        except OSError as e:
            raise ZygoteError(f"sandbox zygote stopped: {e}") from None

    def _receive(self, *, with_fd: bool) -> tuple[bytes, list[int]]:
        try:
            data, fds, _, _ = socket.recv_fds(self._control, 65_536, 1 if with_fd else 0)
        except OSError as e:
            raise ZygoteError(f"sandbox zygote did not answer: {e}") from None
        if not data or len(fds) != int(with_fd):
            raise ZygoteError("sandbox zygote stopped")
        return data, fds


_zygote: Zygote | None = None
_zygote_lock = threading.Lock()


def zygote() -> Zygote:
    """This process's zygote, started on first use and again if it died."""
    global _zygote
    with _zygote_lock:
        if _zygote is None or not _zygote.alive():
            _zygote = Zygote()
        return _zygote


def layers_in_use() -> jail.SandboxLayers | None:
    """The OS layers of this process's zygote, or None when no zygote has been started."""
    with _zygote_lock:
        current = _zygote
    return current.layers() if current is not None and current.alive() else None


def _forget_zygote_in_child() -> None:
    """A forked host must start its own zygote rather than share its parent's socket."""
    global _zygote
    _zygote = None


os.register_at_fork(after_in_child=_forget_zygote_in_child)


class _Server:
    """The zygote's side: forks workers, reports how they ended, kills them on request."""

    def __init__(self, control: socket.socket, layers: jail.SandboxLayers, worker_jail: jail.WorkerJail):
        self.control = control
        self.layers = layers
        self.jail = worker_jail
        # In a PID namespace the host knows workers by other PIDs: found through this process's children.
        self.own_host_pid = int(os.readlink("/proc/self")) if "PID namespace" in layers.in_force else None
        # A child's exit wakes the loop (through this pipe) so that it is reaped at once.
        self.wake_r, self.wake_w = os.pipe()
        os.set_blocking(self.wake_r, False)
        os.set_blocking(self.wake_w, False)
        signal.set_wakeup_fd(self.wake_w)
        signal.signal(signal.SIGCHLD, lambda *_: None)
        self.spares: list[tuple[int, socket.socket]] = []
        self.spare_target = 0
        self.running: set[int] = set()
        self.released: set[int] = set()
        self.exited: dict[int, int] = {}

    def serve(self) -> None:
        while True:
            self.reap()
            idle = 0 if len(self.spares) < self.spare_target else None
            watched: list[socket.socket | int] = [self.control, self.wake_r]
            ready = select.select(watched, [], [], idle)[0]
            if self.wake_r in ready:
                with contextlib.suppress(BlockingIOError):
                    os.read(self.wake_r, 4096)
            if self.control not in ready:
                if not ready:
                    self.spares.append(self.fork())
                continue
            data = self.control.recv(1024)
            if not data:
                break
            request = json.loads(data)
            if request["op"] == "spawn":
                self.spawn(request["count"])
            elif request["op"] == "status":
                self.control.send(json.dumps({"code": self.wait(request["pid"])}).encode())
            elif request["op"] == "release":
                self.release(request["pid"])
            elif request["op"] == "layers":
                self.control.send(self.layers.model_dump_json().encode())
            elif request["op"] == "host_pid":
                self.control.send(json.dumps({"host_pid": self.host_pid(request["pid"])}).encode())
        for pid in self.running:
            _kill_group(pid)
        for pid in self.running:
            os.waitpid(pid, 0)

    def fork(self) -> tuple[int, socket.socket]:
        """A new worker blocked on its socket; its PID and the host's end of that socket."""
        host_end, worker_end = socket.socketpair()
        pid = os.fork()
        if pid == 0:
            with contextlib.suppress(BaseException):  # the worker's stderr is /dev/null: nothing to print
                os.setpgid(0, 0)
                signal.set_wakeup_fd(-1)
                signal.signal(signal.SIGCHLD, signal.SIG_DFL)
                worker.serve(worker_end.fileno(), self.jail)  # closes every other descriptor first
            os._exit(1)
        with contextlib.suppress(OSError):  # it may have done so itself already
            os.setpgid(pid, pid)
        worker_end.close()
        self.running.add(pid)
        return pid, host_end

    def host_pid(self, pid: int) -> int:
        """The worker's PID as the host sees it: outside a PID namespace, the same; -1 if it is gone."""
        if self.own_host_pid is None:
            return pid
        me = self.own_host_pid
        with open(f"/proc/{me}/task/{me}/children") as f:
            children = map(int, f.read().split())
        for child in children:
            with contextlib.suppress(OSError), open(f"/proc/{child}/status") as f:
                ids = next(line for line in f if line.startswith("NSpid:")).split()
                if int(ids[-1]) == pid:
                    return child
        return -1

    def spawn(self, count: int) -> None:
        for _ in range(count):
            pid, host_end = self.spares.pop() if self.spares else self.fork()
            socket.send_fds(self.control, [json.dumps({"pid": pid}).encode()], [host_end.fileno()])
            host_end.close()
        self.spare_target = min(count, MAX_SPARES)

    def reap(self) -> None:
        """Collect every ended child: workers, and in a PID namespace any orphan left to its init."""
        while True:
            try:
                ended = os.waitid(os.P_ALL, 0, os.WEXITED | os.WNOHANG | os.WNOWAIT)
            except ChildProcessError:
                return
            if ended is None:
                return
            pid = ended.si_pid
            if pid in self.running:
                _kill_group(pid)  # anything the worker left in its group; its PID is not reusable until reaped
            status = os.waitpid(pid, 0)[1]
            if pid not in self.running:
                continue  # an orphan this process inherited as the namespace's init
            self.running.discard(pid)
            if pid in self.released:
                self.released.discard(pid)
            else:
                self.exited[pid] = os.waitstatus_to_exitcode(status)

    def wait(self, pid: int) -> int:
        """The worker's exit code; one that has not exited within the grace time is killed."""
        deadline = time.monotonic() + _EXIT_GRACE_S
        while pid in self.running and time.monotonic() < deadline:
            time.sleep(0.001)
            self.reap()
        if pid in self.running:
            _kill_group(pid)
            os.waitpid(pid, 0)
            self.running.discard(pid)
            return -signal.SIGKILL
        return self.exited.pop(pid, -signal.SIGKILL)

    def release(self, pid: int) -> None:
        """Kill the worker and its process group if it runs (reaped later: this never blocks); forget it."""
        if pid in self.running:
            _kill_group(pid)
            self.released.add(pid)
        self.exited.pop(pid, None)


def _kill_group(pid: int) -> None:
    """SIGKILL the process group a worker leads (it may be gone already)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pid, signal.SIGKILL)


def main() -> None:
    """Entry point of the zygote process; its arguments are the control socket's descriptor and the
    memory budget of all its workers together, in MiB.

    Joins the memory cgroup, enters the namespaces, and in a new PID namespace forks the server as its
    init; this process then only waits for the server and exits with its status.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the host's Ctrl-C is the host's to handle
    jail.die_with_parent()
    control = socket.socket(fileno=int(sys.argv[1]))
    cgroup_problem = jail.join_memory_cgroup(int(sys.argv[2]))
    namespaces, missing = jail.enter_namespaces()
    if "PID" in namespaces:
        server = os.fork()
        if server != 0:
            control.close()
            os._exit(os.waitstatus_to_exitcode(os.waitpid(server, 0)[1]) & 0xFF)
        jail.die_with_parent()
    worker_jail = jail.WorkerJail()
    layers = worker_jail.probe(namespaces, missing, cgroup_problem)
    gc.freeze()  # keep the collector off the preloaded objects, so forked workers share their pages
    _Server(control, layers, worker_jail).serve()
