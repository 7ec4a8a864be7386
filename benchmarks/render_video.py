"""How long a rollout video takes to draw: a 10 s quadruped rollout at 30 frames per second, as MP4.

A program walks the quadruped back and forth on a sofa for more than 10 s of simulated time; its states
are recorded and cut at 10 s, then drawn and encoded exactly as ``robotool run --video`` does (default
size, labels, captions, the end held for 2 s). The target: under 30 s of wall time on a 2-core machine
without a GPU (Mesa's software EGL). Also reports what recording costs the run itself.

    MUJOCO_GL=egl python benchmarks/render_video.py [--seconds 10] [--fps 30] [--repeats 2]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import av

from robotool import tasks
from robotool.execute import run
from robotool.render.video import FPS, VIDEO_SIZE, render_video
from robotool.sim import build
from robotool.sim.recorder import StateRecorder, Track

TARGET_S = 30.0
TASK = "sofa_traversing"
CODE = """\
here = get_position("robot")
for _ in range(4):
    walk_to_position([here[0] + 0.5, here[1], here[2]])
    walk_to_position([here[0], here[1], here[2]])
"""


def cut(track: Track, seconds: float) -> Track:
    """The track's states up to ``seconds``."""
    keep = [i for i, t in enumerate(track.times) if t <= seconds + 1e-9]
    return Track(
        times=[track.times[i] for i in keep],
        qpos=[track.qpos[i] for i in keep],
        mocap_pos=[track.mocap_pos[i] for i in keep],
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds to draw")
    parser.add_argument("--fps", type=int, default=FPS)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    task = tasks.load(TASK)
    begun = time.perf_counter()
    run(task, CODE, backend="mujoco")
    plain = time.perf_counter() - begun
    recorder = StateRecorder([0])
    begun = time.perf_counter()
    report = run(task, CODE, backend="mujoco", recorder=recorder)
    recorded = time.perf_counter() - begun
    track = recorder.tracks[0]
    if track.times[-1] < args.seconds:
        print(f"the rollout lasted only {track.times[-1]:.1f} s", file=sys.stderr)
        return 2
    track = cut(track, args.seconds)
    scene = build(task)
    walls = []
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "bench.mp4"
        for _ in range(args.repeats):
            begun = time.perf_counter()
            info = render_video(scene, track, report.rollouts[0], out, fps=args.fps)
            walls.append(time.perf_counter() - begun)
        with av.open(str(out)) as container:
            decoded = sum(1 for _ in container.decode(video=0))
    best = min(walls)
    print(f"run without / with recording: {plain:.2f} s / {recorded:.2f} s")
    print(
        f"video: {args.seconds:g} s simulated + held end, {info.frames} frames ({decoded} decoded) at "
        f"{args.fps} fps, {VIDEO_SIZE[0]}x{VIDEO_SIZE[1]} px"
    )
    print(
        f"draw + encode: best {best:.1f} s, median {statistics.median(walls):.1f} s ({info.frames / best:.1f} frames/s)"
    )
    verdict = "PASS" if best < TARGET_S else "FAIL"
    print(f"{verdict}: target under {TARGET_S:.0f} s")
    return 0 if best < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
