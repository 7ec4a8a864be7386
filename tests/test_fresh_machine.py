"""A machine without EGL/Mesa and without libseccomp: the main job still runs and says in one line what it could not
do and how to get it (the libraries are hidden from a child Python by the fixture ``hidden_libraries``)."""

from __future__ import annotations

import ctypes.util
import json
import os
import subprocess
import sys
from pathlib import Path

FIXTURE = Path(__file__).resolve().parent / "fixtures" / "hidden_libraries"


def _without_libraries(argv: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(FIXTURE), env.get("PYTHONPATH")]))
    env["COLUMNS"] = "400"  # one line stays one line
    return subprocess.run(
        [sys.executable, *argv], cwd=cwd, env=env, capture_output=True, text=True, timeout=300, check=False
    )


def test_the_main_job_runs_without_egl_and_libseccomp_and_says_what_it_could_not_do(tmp_path: Path) -> None:
    out = tmp_path / "results"
    done = _without_libraries(
        ["-m", "robotool.eval", "--tasks", "milk_reaching_near", "--methods", "no_tool", "--out", str(out)], tmp_path
    )
    said = done.stdout + done.stderr
    assert done.returncode == 0, said
    assert "Traceback" not in said
    assert json.loads((out / "results.json").read_text())["records"]
    seccomp = [line for line in done.stderr.splitlines() if "WITHOUT the seccomp filter" in line]
    assert len(seccomp) == 1 and seccomp[0].startswith("warning: ") and "apt-get install libseccomp2" in seccomp[0]
    pictures = [line for line in done.stdout.splitlines() if "no pictures" in line]
    assert len(pictures) == 1 and "no EGL library" in pictures[0] and "libegl1" in pictures[0]
    assert "no pictures" in (out / "report.md").read_text()


def test_drawing_without_egl_is_one_line_naming_the_packages(tmp_path: Path) -> None:
    done = _without_libraries(["-m", "robotool", "render", "sofa_traversing", "--out", "scene.png"], tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "libegl1" in lines[0]
    assert not (tmp_path / "scene.png").exists()


def _with_gl(value: str, argv: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MUJOCO_GL": value, "COLUMNS": "400"}
    return subprocess.run(
        [sys.executable, "-m", "robotool", *argv], cwd=cwd, env=env, capture_output=True, text=True, timeout=300
    )


def test_a_mujoco_gl_that_mujoco_cannot_import_with_switches_drawing_off_saying_why(tmp_path: Path) -> None:
    """Found by an adversarial run: ``MUJOCO_GL=junk`` (or OSMesa without its library) made every command, ``--help``
    included, end in MuJoCo's import traceback. Now only drawing is off, and a drawing command says why in one line."""
    cases = [("junk", "MUJOCO_GL='junk' is not an OpenGL back end")]
    if ctypes.util.find_library("OSMesa") is None:  # (where it is installed, osmesa draws)
        cases.append(("osmesa", "OSMesa library"))
    for value, why in cases:
        described = _with_gl(value, ["describe", "milk_reaching"], tmp_path)
        assert described.returncode == 0 and "Grasp the milk carton" in described.stdout, described.stderr
        drawn = _with_gl(value, ["render", "milk_reaching", "--out", "scene.png"], tmp_path)
        lines = drawn.stderr.strip().splitlines()
        assert drawn.returncode == 2 and len(lines) == 1 and why in lines[0], drawn.stderr
