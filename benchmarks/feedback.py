"""The three figures of fast feedback, each measured in one run: the README's test command, the main job, and
the lockstep runner against raw MuJoCo.

- tests: the README's test command (its quick start's second line, ``ruff check . && pytest``), run as written in
  the repository root, timed as a whole (wall seconds); its summary line (passed, skipped, failed) is printed.
- main job: ``python -m robotool.eval`` with no model (the README's main job), into a scratch folder; wall seconds
  of the whole command, and the number of runs its results.json holds.
- sim: ``benchmarks/sim_throughput.py --sizes 64 --backends mujoco`` (both robots); its runner/replay column.

The machine's load average is printed before and after each figure: on a shared machine the wall times are
inflated by what else runs, so compare figures taken back to back on the same load.

    python benchmarks/feedback.py                        # all three (the test command takes minutes)
    python benchmarks/feedback.py --only eval sim        # the main job and the runner only
    python benchmarks/feedback.py --only tests --pytest-args -m "not slow"   # the quick check instead
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGETS = {"tests": "<= 300 s on 2 cores", "eval": "<= 90 s on 2 cores", "sim": ">= 0.9 arm, >= 0.8 quadruped"}


def quick_start() -> list[str]:
    """The README's quick start lines, as ``.ci/quick_start.py`` prints them."""
    done = subprocess.run(
        [sys.executable, str(ROOT / ".ci" / "quick_start.py")], capture_output=True, text=True, check=True
    )
    return done.stdout.splitlines()


def timed(argv: list[str], *, shell: bool = False, cwd: Path = ROOT) -> tuple[float, subprocess.CompletedProcess[str]]:
    """Wall seconds of one command (its output captured) and how it ended."""
    path = os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")])  # ruff, pytest
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PATH": path}
    started = time.perf_counter()
    done = subprocess.run(
        argv if not shell else ["bash", "-o", "pipefail", "-c", argv[0]],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    return time.perf_counter() - started, done


def load() -> str:
    return f"{os.getloadavg()[0]:.1f}"


def test_command(extra: list[str]) -> tuple[str, str]:
    """(wall time, note) of the README's test command, ``extra`` appended to its pytest."""
    command = quick_start()[1]
    if extra:
        command = command + " " + " ".join(extra)
    wall, done = timed([command], shell=True)
    summary = next((line for line in reversed(done.stdout.splitlines()) if re.search(r" in [\d.]+s", line)), "")
    note = f"`{command}`: exit {done.returncode}; {summary.strip('= ')}"
    return f"{wall:.0f} s", note


def main_job() -> tuple[str, str]:
    """(wall time, note) of ``python -m robotool.eval`` into a scratch folder."""
    with tempfile.TemporaryDirectory(prefix="robotool-feedback-") as scratch:
        out = Path(scratch) / "results"
        wall, done = timed([sys.executable, "-m", "robotool.eval", "--out", str(out)], cwd=Path(scratch))
        results = out / "results.json"
        runs = len(json.loads(results.read_text())["records"]) if results.exists() else 0
    return f"{wall:.0f} s", f"`python -m robotool.eval`: exit {done.returncode}; {runs} runs"


def sim_ratio() -> tuple[str, str]:
    """(runner/replay per robot, note) from ``sim_throughput.py --sizes 64 --backends mujoco``."""
    script = ROOT / "benchmarks" / "sim_throughput.py"
    _, done = timed([sys.executable, str(script), "--sizes", "64", "--backends", "mujoco"])
    ratios = []
    for line in done.stdout.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 9 and cells[1] == "64":
            ratios.append(f"{cells[0].split(':')[0]} {cells[5]}")
    return ", ".join(ratios) or "-", f"`sim_throughput.py --sizes 64 --backends mujoco`: exit {done.returncode}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="+", choices=list(TARGETS), default=list(TARGETS))
    parser.add_argument("--pytest-args", nargs=argparse.REMAINDER, default=[], help="appended to the test command")
    args = parser.parse_args()
    measures = {"tests": lambda: test_command(args.pytest_args), "eval": main_job, "sim": sim_ratio}
    print(f"{os.cpu_count()} CPU(s)\n")
    print("| figure | target | measured | load before | load after | how |")
    print("| --- | --- | ---: | ---: | ---: | --- |")
    for name in args.only:
        before = load()
        figure, note = measures[name]()
        print(f"| {name} | {TARGETS[name]} | {figure} | {before} | {load()} | {note} |", flush=True)


if __name__ == "__main__":
    main()
