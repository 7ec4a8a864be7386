"""The operating-system layers around a worker, which hold even if a program defeats the Python-level checks.

The Python-level layers (the validator and the worker's restricted namespace) assume that the
allowlisted C code is memory-safe; it is not always (numpy has had buffer and dtype primitives that
forge references). So every worker also runs behind these layers, each detected when the zygote
starts and reported as :class:`SandboxLayers`:

- **seccomp**: a seccomp-bpf filter (compiled once by libseccomp, through ``pyseccomp``), loaded in
  each worker before the program's text is compiled, allows only what a running worker needs: reading
  and writing its socket to the host, memory management (never executable, only an allocator's
  advice), time, plain futex waits and wakes, signal return and exit.
  Every other system call (open, socket, exec, fork, kill, ptrace, sigaction, ...) fails with
  ``EPERM``; a call through a foreign ABI (i386, x32) kills the worker.
- **namespaces**: the zygote moves into new PID, network, IPC and mount namespaces (inside a user
  namespace when not root). Workers see no host process, no network interface, and when the zygote
  ends the kernel kills everything left in the PID namespace.
- **empty root**: each worker ``chroot``s into a directory (mode 0700, owned by the host's user) that
  was deleted right after it was made, so no file can be named, listed or created.
- **memory cgroup**: the zygote moves into a memory cgroup (v2 ``memory.max``, or v1
  ``memory.limit_in_bytes``) capped at the sandbox memory budget, so every worker it forks is in it too:
  however many batches and hosts run at once, their workers together cannot take more of the
  machine's memory (the kernel kills the largest worker inside the cgroup instead). Sandboxes with
  the same budget under the same parent cgroup share one.
- **unprivileged uid**: workers drop to ``nobody`` (when the host runs as root) and every capability
  (also those a user namespace grants), set no-new-privileges and are not dumpable, so their
  ``/proc`` entries and memory are closed to each other.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import os
import socket
import tempfile
import warnings
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict

from robotool.errors import RobotoolWarning

NOBODY = 65534
"""The uid and gid workers run as when the host is root."""

SOCKET_FD = 3
"""The worker's socket to the host: the only descriptor it may read or write under seccomp."""

ALLOWED_SYSCALLS: tuple[str, ...] = (
    "munmap", "mremap", "brk",
    "clock_gettime", "clock_getres", "gettimeofday", "clock_nanosleep", "nanosleep", "sched_yield",
    "rt_sigreturn", "getpid", "gettid", "exit", "exit_group",
)  # fmt: skip
"""System calls a running worker may make with any arguments (found by tracing workers running numpy)."""

SOCKET_SYSCALLS: tuple[str, ...] = ("read", "write")
"""System calls a running worker may make on :data:`SOCKET_FD` only."""

NO_EXEC_SYSCALLS: tuple[str, ...] = ("mmap", "mprotect")
"""System calls a running worker may make only without ``PROT_EXEC``: it never needs new machine code."""

_PROT_EXEC = 4

FUTEX_OPERATIONS: tuple[int, ...] = (0, 1, 9, 10)
"""``futex`` operations a running worker may use, on its private memory only: wait and wake, plain and with a
bit set (glibc's locks and condition variables). Not the priority-inheritance and requeue operations, whose
kernel code is behind several root exploits."""

_FUTEX_PRIVATE = 128
_FUTEX_CLOCK_REALTIME = 256

MADVISE_ADVICE: tuple[int, ...] = (0, 1, 2, 3, 4, 8, 14, 15)
"""``madvise`` advice a running worker may give: what allocators use (normal, random, sequential, will
need, don't need, free, huge pages or not). Not page merging across processes (a side channel), page-out,
population, fork behaviour or memory poisoning."""

_NAMESPACES: dict[str, int] = {"PID": 0x20000000, "network": 0x40000000, "IPC": 0x08000000, "mount": 0x00020000}
_CLONE_NEWUSER = 0x10000000
_PR_SET_PDEATHSIG = 1
_PR_SET_DUMPABLE = 4
_PR_SET_NO_NEW_PRIVS = 38
_PR_SET_SECCOMP = 22
_SECCOMP_MODE_FILTER = 2

_libc = ctypes.CDLL(None, use_errno=True)


class SandboxLayers(BaseModel):
    """The OS layers that confine workers (``in_force``) and those that could not be set up, with why."""

    model_config = ConfigDict(frozen=True)

    in_force: list[str]
    missing: dict[str, str]

    @property
    def seccomp(self) -> bool:
        return "seccomp filter" in self.in_force

    def summary(self) -> str:
        """One line: the layers in force, then the missing ones with their reasons."""
        line = "sandbox: " + (", ".join(self.in_force) or "no OS layers")
        if self.missing:
            line += "; missing: " + "; ".join(f"{name} ({why})" for name, why in self.missing.items())
        return line

    def warning(self) -> str | None:
        """A loud warning when the seccomp filter, the layer that must hold, is not in force."""
        if self.seccomp:
            return None
        why = self.missing.get("seccomp filter", "unknown reason")
        return (
            f"generated programs run WITHOUT the seccomp filter ({why}): a program that defeats the "
            "Python-level checks can make any system call its uid allows; install libseccomp "
            "(Debian: apt-get install libseccomp2)"
        )


class SandboxWarning(RobotoolWarning):
    """Issued once when workers run without their seccomp filter."""


def _unshare(flags: int) -> None:
    if _libc.unshare(flags) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code))


def _prctl(option: int, value: int) -> None:
    if _libc.prctl(option, value, 0, 0, 0) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code))


class _CapabilityHeader(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]


class _CapabilitySets(ctypes.Structure):
    _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32), ("inheritable", ctypes.c_uint32)]


def _drop_capabilities() -> None:
    """Clear every capability of this process (a worker in a user namespace starts with all of them there)."""
    header = _CapabilityHeader(0x20080522, 0)  # _LINUX_CAPABILITY_VERSION_3: two 32-bit sets
    sets = (_CapabilitySets * 2)()
    if _libc.capset(ctypes.byref(header), sets) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code))


def die_with_parent() -> None:
    """SIGKILL this process when its parent ends (the host, or the zygote for a worker)."""
    _prctl(_PR_SET_PDEATHSIG, 9)


def enter_namespaces() -> tuple[list[str], dict[str, str]]:
    """Move this (single-threaded) process into new namespaces; those entered, and why others failed.

    After a new PID namespace the caller must fork: its first child is the namespace's init.
    """
    entered: list[str] = []
    missing: dict[str, str] = {}
    if os.geteuid() != 0:
        uid, gid = os.getuid(), os.getgid()
        try:
            _unshare(_CLONE_NEWUSER)
            for name, text in (("setgroups", "deny"), ("uid_map", f"{uid} {uid} 1"), ("gid_map", f"{gid} {gid} 1")):
                with open(f"/proc/self/{name}", "w") as f:
                    f.write(text)
            entered.append("user namespace")
        except OSError as e:
            missing["user namespace"] = e.strerror or str(e)
    for name, flag in _NAMESPACES.items():
        try:
            _unshare(flag)
            entered.append(name)
        except OSError as e:
            missing[f"{name} namespace"] = e.strerror or str(e)
    return entered, missing


def join_memory_cgroup(limit_mb: int) -> str | None:
    """Move this process (and so every process it forks later) into the memory cgroup
    ``robotool-sandbox-<limit_mb>mb`` (placed by :func:`_memory_cgroup_directory`), capped at ``limit_mb``;
    None, or why not."""
    try:
        directory, limit_file = _memory_cgroup_directory()
        directory = directory / f"robotool-sandbox-{limit_mb}mb"
        directory.mkdir(exist_ok=True)
        (directory / limit_file).write_text(str(limit_mb * 2**20))
        (directory / "cgroup.procs").write_text(str(os.getpid()))
    except (OSError, ValueError) as e:
        return str(e)
    return None


def _memory_cgroup_directory() -> tuple[Path, str]:
    """Where to make the sandbox's memory cgroup (v1: inside this process's own; v2: next to it) and the
    name of its limit file (``memory.max`` on v2, ``memory.limit_in_bytes`` on v1); ``ValueError`` when
    there is no memory controller to use."""
    mounts = [line.split() for line in Path("/proc/self/mounts").read_text().splitlines()]
    for line in Path("/proc/self/cgroup").read_text().splitlines():
        _, controllers, path = line.split(":", 2)
        if "memory" in controllers.split(","):
            v1 = next((m[1] for m in mounts if m[2] == "cgroup" and "memory" in m[3].split(",")), None)
            if v1 is not None:
                return Path(v1 + path), "memory.limit_in_bytes"
        elif controllers == "":  # v2: a process may only sit in a leaf, so the new cgroup is a sibling
            for mount in (m[1] for m in mounts if m[2] == "cgroup2"):
                parent = Path(mount + path) if path == "/" else Path(mount + path).parent
                if "memory" in (parent / "cgroup.subtree_control").read_text().split():
                    return parent, "memory.max"
    raise ValueError("no memory cgroup controller is available to this process")


class _FilterProgram(ctypes.Structure):
    """``struct sock_fprog``: a BPF program for ``prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ...)``."""

    _fields_ = [("length", ctypes.c_ushort), ("instructions", ctypes.c_void_p)]


def _syscall_filter() -> tuple[Any, str | None]:
    """The worker's seccomp filter as a BPF program, compiled once by libseccomp (each worker only
    hands it to the kernel); or None and why not."""
    try:
        import pyseccomp as seccomp
    except (ImportError, RuntimeError, OSError) as e:  # RuntimeError: libseccomp.so.2 is missing
        return None, f"pyseccomp/libseccomp unavailable: {e}"
    try:
        syscall_filter = seccomp.SyscallFilter(seccomp.ERRNO(errno.EPERM))
        for name in ALLOWED_SYSCALLS:
            syscall_filter.add_rule(seccomp.ALLOW, name)
        for name in SOCKET_SYSCALLS:
            syscall_filter.add_rule(seccomp.ALLOW, name, seccomp.Arg(0, seccomp.EQ, SOCKET_FD))
        for name in NO_EXEC_SYSCALLS:
            syscall_filter.add_rule(seccomp.ALLOW, name, seccomp.Arg(2, seccomp.MASKED_EQ, _PROT_EXEC, 0))
        futex_mask = 0xFFFFFFFF & ~_FUTEX_CLOCK_REALTIME  # the kernel reads the operation's low 32 bits only
        for operation in FUTEX_OPERATIONS:
            private = seccomp.Arg(1, seccomp.MASKED_EQ, futex_mask, operation | _FUTEX_PRIVATE)
            syscall_filter.add_rule(seccomp.ALLOW, "futex", private)
        for advice in MADVISE_ADVICE:
            syscall_filter.add_rule(seccomp.ALLOW, "madvise", seccomp.Arg(2, seccomp.EQ, advice))
        with tempfile.TemporaryFile() as compiled:
            syscall_filter.export_bpf(compiled)
            compiled.seek(0)
            instructions = ctypes.create_string_buffer(compiled.read())
    except (OSError, ValueError, RuntimeError) as e:
        return None, f"libseccomp refused the filter: {e}"
    program = _FilterProgram(len(instructions.raw) // 8, ctypes.addressof(instructions))
    return (program, instructions), None  # the buffer travels with the program that points into it


def _empty_root() -> int | None:
    """A descriptor of a directory deleted right after it was made: nothing can be created in it."""
    path = tempfile.mkdtemp(prefix="robotool-root-")
    try:
        opened = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return None
    finally:
        os.rmdir(path)
    kept = fcntl.fcntl(opened, fcntl.F_DUPFD, 10)  # clear of descriptors 0-3, which a worker rearranges
    os.close(opened)
    return kept


class WorkerJail:
    """The per-worker layers, prepared once in the zygote and applied in every forked worker."""

    def __init__(self) -> None:
        self._root_fd = _empty_root()
        self._filter, self._filter_problem = _syscall_filter()
        self._drop_uid = os.geteuid() == 0

    def enter(self) -> None:
        """Empty root, unprivileged uid, no capabilities, no new privileges, not dumpable, death with
        the zygote; each where it works.

        Called in the worker before it waits for its program; whatever fails is absent from the
        layers the probe reported, and the rest still apply. The worker also becomes the kernel's first
        choice when memory runs out (in its cgroup or on the machine), before the zygote or the host.
        """
        with contextlib.suppress(OSError), open("/proc/self/oom_score_adj", "w") as adjust:
            adjust.write("1000")
        if self._root_fd is not None:
            with contextlib.suppress(OSError):
                os.fchdir(self._root_fd)
                os.chroot(".")
            os.close(self._root_fd)
        if self._drop_uid:
            with contextlib.suppress(OSError):
                os.setgroups([])
                os.setresgid(NOBODY, NOBODY, NOBODY)
                os.setresuid(NOBODY, NOBODY, NOBODY)
        with contextlib.suppress(OSError):
            _drop_capabilities()
        with contextlib.suppress(OSError):
            _prctl(_PR_SET_NO_NEW_PRIVS, 1)
            _prctl(_PR_SET_DUMPABLE, 0)
        die_with_parent()  # after the uid change, which clears the parent-death signal

    def seal(self) -> None:
        """Load the seccomp filter: from here on only :data:`ALLOWED_SYSCALLS` and the socket work.

        Needs no-new-privileges (set by :meth:`enter`) unless the process is privileged; raises
        ``OSError`` when the kernel refuses, so that a worker never runs its program unfiltered.
        """
        if self._filter is not None:
            program, _ = self._filter
            if _libc.prctl(_PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, ctypes.byref(program), 0, 0) != 0:
                code = ctypes.get_errno()
                raise OSError(code, os.strerror(code))

    def probe(self, namespaces: list[str], missing: dict[str, str], cgroup_problem: str | None) -> SandboxLayers:
        """Apply every layer in a throw-away child and test each; the layers that held (with the memory
        cgroup, which the caller joined or could not: ``cgroup_problem``)."""
        read_end, write_end = os.pipe()
        pid = os.fork()
        if pid == 0:  # the probe child: report a bit per layer that held, then exit
            held = 0
            with contextlib.suppress(BaseException):
                os.close(read_end)
                self.enter()
                os.dup2(write_end, SOCKET_FD)  # the one descriptor a sealed worker may write
                held |= 0 if os.path.exists("/proc/self") else 1
                held |= 2 if os.getuid() != 0 and os.geteuid() != 0 else 0
                self.seal()
                try:
                    socket.socket(socket.AF_UNIX, socket.SOCK_STREAM).close()
                except PermissionError:
                    held |= 4
                os.write(SOCKET_FD, bytes([held]))
            os._exit(0)
        os.close(write_end)
        reply = os.read(read_end, 1)
        os.close(read_end)
        os.waitpid(pid, 0)
        held = reply[0] if reply else 0
        layers = [f"{name} namespace" if name != "user namespace" else name for name in namespaces]
        missing = dict(missing)
        if cgroup_problem is None:
            layers.append("memory cgroup")
        else:
            missing["memory cgroup"] = cgroup_problem
        for bit, layer, why in (
            (1, "empty root", "chroot is not permitted"),
            (2, "uid nobody", "the host does not run as root"),
            (4, "seccomp filter", self._filter_problem or "the kernel refused the filter"),
        ):
            if held & bit:
                layers.append(layer)
            elif not (bit == 2 and not self._drop_uid and "user namespace" in namespaces):
                missing[layer] = why
        return SandboxLayers(in_force=layers, missing=missing)


def warn_if_weak(layers: SandboxLayers) -> None:
    """Issue a :class:`SandboxWarning` when the seccomp filter is not in force."""
    message = layers.warning()
    if message is not None:
        warnings.warn(message, SandboxWarning, stacklevel=3)
