"""Rollout videos: recorded states drawn frame by frame, captioned from the rollout's trace, encoded as MP4.

States are recorded at every control tick (:class:`~robotool.sim.recorder.StateRecorder`); a frame between
two ticks shows the positions interpolated between them (``mj_differentiatePos`` / ``mj_integratePos``, so
rotations stay rotations). The caption names the skill running at that time; a skill that did not end
``done`` (refused, stalled, timed out, failed) is shown in red for a while from when it ended; the last
frame is held with the goal's end state (reached, or which conditions failed and why the world failed).
Encoding uses PyAV (FFmpeg's libraries, shipped in its wheel) with H.264 in ``yuv420p`` for players (MPEG-4
Part 2 where the FFmpeg build has no H.264 encoder).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from robotool.render.overlay import CaptionLine
from robotool.render.painter import Painter, RenderError
from robotool.render.still import scene_title
from robotool.rollout import Rollout, SkillCall
from robotool.sim.compiled_scene import Scene
from robotool.sim.recorder import Track

FPS = 30
VIDEO_SIZE = (640, 360)  # px, width x height (both even, as yuv420p needs)
HOLD_S = 2.0  # s the end state stays on screen
MARK_S = 2.0  # s a refusal or failure stays in the caption after it happened
BOUNDS_SAMPLES = 40  # recorded states the camera keeps in view (spread over the rollout)
RED, GREEN = (255, 110, 100), (120, 230, 130)
ENCODERS = ("libx264", "libopenh264", "mpeg4")  # in order of preference


@dataclass(frozen=True)
class VideoInfo:
    """What was written: the file, its frame count and frame rate, and the seconds it covers."""

    path: Path
    frames: int
    fps: int
    duration: float


def _args_text(args: Sequence[object]) -> str:
    def one(a: object) -> str:
        if isinstance(a, list):
            return "[" + ", ".join(f"{v:.2f}" if isinstance(v, float) else str(v) for v in a) + "]"
        return repr(a) if isinstance(a, str) else str(a)

    return ", ".join(one(a) for a in args)


def _call_text(call: SkillCall) -> str:
    return f"{call.skill}({_args_text(call.args)})"


def _outcome_text(call: SkillCall) -> str:
    return f"{call.skill} {call.outcome}" + (f": {call.reason}" if call.reason else "")


def end_lines(rollout: Rollout, *, goal_missed: bool = True) -> list[CaptionLine]:
    """The goal's end state: reached, or the failed conditions (a fragile object's fall named) and the error.

    ``goal_missed=False`` leaves out the line that says the goal was not reached (for a caption that says so)."""
    if rollout.success:
        return [CaptionLine("goal reached: " + ", ".join(rollout.conditions), GREEN)]
    lines = []
    if rollout.error:
        lines.append(CaptionLine(f"world failed: {rollout.error}", RED))
    unmet = [name for name, ok in rollout.conditions.items() if not ok]
    for broke in (e for e in rollout.events if e.kind == "broke"):
        m = broke.measured
        fall = f"in a fall of {m.get('fall', 0.0):.2f} m"
        how = f"struck at {m['strike_speed']:.1f} m/s" if "strike_speed" in m else fall
        lines.append(CaptionLine(f"{broke.object} broke {how}", RED))
    if goal_missed:
        lines.append(CaptionLine("goal not reached" + (": " + ", ".join(unmet) + " false" if unmet else ""), RED))
    return lines


def caption_at(rollout: Rollout, t: float) -> list[CaptionLine]:
    """The caption of the frame at ``t`` seconds: the running skill, recent failures, or the end state."""
    if t >= rollout.sim_time:
        last = [c for c in rollout.calls if c.outcome != "done" and c.ended >= rollout.sim_time - MARK_S][-1:]
        return [CaptionLine(_outcome_text(c), RED) for c in last] + end_lines(rollout)
    lines = []
    for call in rollout.calls:
        if call.outcome != "done" and call.ended <= t < call.ended + MARK_S:
            lines.append(CaptionLine(_outcome_text(call), RED))
        elif call.started <= t < call.ended:
            lines.append(CaptionLine(_call_text(call)))
    return lines[-3:]


def frame_times(track: Track, fps: int) -> np.ndarray:
    """Times of the frames: from the first recorded state to the last, then the last held for :data:`HOLD_S`."""
    end = track.times[-1]
    return np.arange(round((end + HOLD_S) * fps) + 1) / fps


class _Interpolator:
    """Positions at any time between recorded states."""

    def __init__(self, model: mujoco.MjModel, track: Track):
        self.model = model
        self.times, self.qpos, self.mocap = track.arrays()
        self._qvel = np.zeros(model.nv)

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        times = self.times
        i = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1))
        if i == len(times) - 1 or t <= times[i]:
            return self.qpos[i].copy(), self.mocap[i]
        alpha = (t - times[i]) / (times[i + 1] - times[i])
        mujoco.mj_differentiatePos(self.model, self._qvel, 1.0, self.qpos[i], self.qpos[i + 1])
        qpos = self.qpos[i].copy()
        mujoco.mj_integratePos(self.model, qpos, self._qvel, alpha)
        mocap = self.mocap[i] + alpha * (self.mocap[i + 1] - self.mocap[i])
        return qpos, mocap


def frames(
    scene: Scene,
    track: Track,
    rollout: Rollout,
    *,
    fps: int = FPS,
    width: int = VIDEO_SIZE[0],
    height: int = VIDEO_SIZE[1],
) -> Iterator[np.ndarray]:
    """The video's frames (height, width, 3) uint8, captioned, from one camera that sees the whole rollout."""
    if not len(track):
        raise RenderError("nothing was recorded for this world")
    _, qpos, _ = track.arrays()
    spread = qpos[np.unique(np.linspace(0, len(qpos) - 1, BOUNDS_SAMPLES).round().astype(int))]
    painter = Painter(scene, width, height, frame_qpos=spread, shadows=False)
    states = _Interpolator(painter.drawing.model, track)
    title = scene_title(scene.task)
    try:
        for t in frame_times(track, fps):
            painter.set_state(*states.at(float(t)))
            head = CaptionLine(f"{title.text}   world {rollout.world}  t = {min(t, track.times[-1]):.2f} s")
            image = painter.picture(title=[head], caption=caption_at(rollout, float(t)))
            yield np.asarray(image)
    finally:
        painter.close()


def _encoder(available: set[str]) -> str:
    """H.264 (x264, else OpenH264) where this FFmpeg build has it, else MPEG-4 Part 2 (both play in MP4)."""
    for name in ENCODERS:
        if name in available:
            return name
    raise RenderError(f"this FFmpeg build has none of the video encoders {', '.join(ENCODERS)}")


def write_mp4(path: Path, images: Iterator[np.ndarray], *, fps: int, width: int, height: int) -> int:
    """Encode RGB frames as H.264 MP4 at ``path``; returns the number of frames written."""
    try:
        import av
    except ImportError:
        raise RenderError("writing videos needs PyAV: pip install 'robotool[render]'") from None

    if width % 2 or height % 2:
        raise RenderError(f"video size {width}x{height} must be even in both directions")
    count = 0
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with av.open(str(path), mode="w", format="mp4") as container:
            encoder = _encoder(av.codecs_available)
            stream = container.add_stream(encoder, rate=fps)
            assert isinstance(stream, av.VideoStream)  # a video codec's stream
            stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
            if encoder == "libx264":
                stream.options = {"crf": "23", "preset": "veryfast"}
            for pixels in images:
                container.mux(stream.encode(av.VideoFrame.from_ndarray(pixels, format="rgb24")))
                count += 1
            container.mux(stream.encode(None))
    except OSError as e:  # PyAV's file errors are OSErrors too
        raise RenderError(f"cannot write {path}: {e.strerror or e}") from None
    return count


def render_video(
    scene: Scene,
    track: Track,
    rollout: Rollout,
    out: Path,
    *,
    fps: int = FPS,
    width: int = VIDEO_SIZE[0],
    height: int = VIDEO_SIZE[1],
) -> VideoInfo:
    """Draw one recorded world's rollout to the MP4 ``out``."""
    count = write_mp4(
        out, frames(scene, track, rollout, fps=fps, width=width, height=height), fps=fps, width=width, height=height
    )
    return VideoInfo(path=out, frames=count, fps=fps, duration=track.times[-1])
