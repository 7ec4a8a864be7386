"""Pictures and videos: every built-in task drawn headless, labels on their objects, a captioned MP4 rollout.

Pictures are small and the rollout short (a tool-free program refused after 2.5 s) to keep this fast;
rendering runs on the CPU through Mesa's EGL when there is no GPU.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from pathlib import Path

import av
import numpy as np
import pytest
from fixtures.reference import program, program_path
from PIL import Image

from robotool import tasks
from robotool.cli import main
from robotool.eval.records import Results
from robotool.render.painter import Painter
from robotool.render.picture_model import GOAL_RGBA, ROBOT_RGBA
from robotool.render.run_videos import video_paths
from robotool.render.still import render_scene
from robotool.render.top_view import plan_figure, write_plan
from robotool.render.video import MARK_S, VIDEO_SIZE, caption_at, end_lines, frame_times, render_video
from robotool.rollout import Event, Rollout, SkillCall
from robotool.sim.recorder import StateRecorder
from robotool.task.task_model import Task

SMALL = (240, 136)  # px
VIDEO = (160, 96)  # px, even
FPS = 10
VASE_BROKE = Event(kind="broke", time=5.0, object="vase", measured={"fall": 0.62, "max_drop": 0.3},
                   detail="the ground")


def status(argv: list[str]) -> int:
    """``robotool ARGV`` in-process: its exit status, also when argparse exits for a bad option."""
    try:
        return main(argv)
    except SystemExit as e:
        return int(e.code or 0)


def _hue_pixels(pixels: np.ndarray, rgba: tuple[float, ...], tolerance: float = 12.0) -> np.ndarray:
    """Mask of saturated pixels with the hue of ``rgba`` (shading changes brightness, not hue)."""
    hsv = np.asarray(Image.fromarray(pixels).convert("HSV")).astype(float)
    target = np.asarray(Image.fromarray(np.uint8([[np.array(rgba[:3]) * 255]])).convert("HSV")).astype(float)[0, 0]
    hue_gap = np.abs(hsv[..., 0] - target[0])
    hue_gap = np.minimum(hue_gap, 256 - hue_gap)
    return (hue_gap <= tolerance) & (hsv[..., 1] > 100)


@pytest.mark.parametrize("name", tasks.names())
def test_every_builtin_task_renders_with_robot_and_goal_in_view(tmp_path: Path, sim_scene, name: str) -> None:
    out = render_scene(sim_scene(name), tmp_path / f"{name}.png", width=SMALL[0], height=SMALL[1])
    pixels = np.asarray(Image.open(out).convert("RGB"))
    assert pixels.shape == (SMALL[1], SMALL[0], 3)
    background = np.median(pixels.reshape(-1, 3), axis=0)
    differs = np.abs(pixels.astype(int) - background).sum(axis=2) > 40
    assert differs.mean() > 0.05, "the picture is (nearly) all background"
    assert _hue_pixels(pixels, ROBOT_RGBA).sum() > 20, "the robot is not in the picture"
    assert _hue_pixels(pixels, GOAL_RGBA).sum() > 5, "the goal's object is not in the picture"


@functools.cache
def _painter(name: str) -> Painter:
    from robotool.sim import build

    return Painter(build(tasks.load(name)), *SMALL)


@pytest.mark.parametrize("name", tasks.names())
def test_labels_name_every_object_at_its_place_in_the_picture(name: str) -> None:
    painter = _painter(name)
    pixels = painter.pixels()
    labels = {label.text: label for label in painter.labels()}
    task = tasks.load(name)
    expected = {o.name + (" (goal)" if o.name == task.goal.object else "") for o in task.objects} | {"robot"}
    assert set(labels) == expected
    for label in labels.values():
        x, y = label.anchor
        assert 0 <= x < SMALL[0] and 0 <= y < SMALL[1], f"{label.text} is outside the picture"
    x, y = (round(v) for v in labels["robot"].anchor)  # the top of the robot: robot-coloured pixels around it
    window = pixels[max(0, y - 4) : y + 6, max(0, x - 5) : x + 6]
    assert _hue_pixels(window, ROBOT_RGBA).any()


def test_render_command_writes_a_png_and_refuses_other_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "scene.png"
    assert status(["render", "sofa_traversing", "--out", str(out), "--width", "200", "--height", "120"]) == 0
    assert Image.open(out).size == (200, 120)
    assert status(["render", "sofa_traversing", "--out", str(tmp_path / "scene.jpg")]) == 2
    assert status(["render", "sofa_traversing", "--out", str(out), "--width", "4"]) == 2
    assert status(["render", "sofa_traversing", "--out", "/proc/robotool-scene.png"]) == 2
    err = capsys.readouterr().err
    assert "must name a .png file" in err and "picture size 4x540" in err and "Traceback" not in err
    assert "cannot write /proc/robotool-scene.png" in err


def _refused_rollout(run_texts) -> tuple[Rollout, StateRecorder]:
    recorder = StateRecorder([0])
    rollout = run_texts(
        tasks.load("sofa_traversing"),
        [program("sofa_traversing_direct")],
        backend="mujoco",
        perturb=False,
        recorder=recorder,
    )[0]
    return rollout, recorder


def test_recording_keeps_the_states_and_changes_no_outcome(run_texts) -> None:
    recorded, recorder = _refused_rollout(run_texts)
    plain = run_texts(
        tasks.load("sofa_traversing"), [program("sofa_traversing_direct")], backend="mujoco", perturb=False
    )[0]
    assert recorded == plain
    times, qpos, _ = recorder.tracks[0].arrays()
    assert times[0] == 0.0 and np.all(np.diff(times) > 0)
    assert times[-1] == pytest.approx(recorded.sim_time)
    assert qpos.shape[0] == len(times) and np.isfinite(qpos).all()
    with pytest.raises(ValueError, match="cannot record world"):
        run_texts(
            tasks.load("sofa_traversing"),
            [program("sofa_traversing_direct")],
            backend="mujoco",
            recorder=StateRecorder([3]),
        )


def test_rollout_video_opens_with_the_expected_frames(tmp_path: Path, sim_scene, run_texts) -> None:
    rollout, recorder = _refused_rollout(run_texts)
    assert not rollout.success and any(c.outcome == "refused" for c in rollout.calls)
    info = render_video(
        sim_scene("sofa_traversing"),
        recorder.tracks[0],
        rollout,
        tmp_path / "w0.mp4",
        fps=FPS,
        width=VIDEO[0],
        height=VIDEO[1],
    )
    expected = len(frame_times(recorder.tracks[0], FPS))
    assert info.frames == expected
    with av.open(str(info.path)) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name in ("h264", "mpeg4") and (stream.width, stream.height) == VIDEO
        decoded = [frame.to_ndarray(format="rgb24") for frame in container.decode(stream)]
    assert len(decoded) == expected
    assert np.abs(decoded[0].astype(int) - decoded[-1].astype(int)).mean() > 1, "the robot did not move"


def test_captions_mark_refusals_for_a_while_and_the_goal_at_the_end() -> None:
    walk = SkillCall(skill="walk_to_position", args=[[1.0, 0.0, 0.0]], outcome="done", started=0.0, ended=1.0)
    refused = SkillCall(
        skill="climb_to_position",
        args=[[2.0, 0.0, 0.3]],
        outcome="refused",
        reason="step too high",
        started=1.0,
        ended=1.2,
    )
    query = SkillCall(skill="get_position", args=["sofa"], outcome="done", started=1.2, ended=1.2)
    walk_back = SkillCall(skill="walk_to_position", args=[[0.0, 0.0, 0.0]], outcome="done", started=1.2, ended=6.0)
    rollout = Rollout(
        world=0,
        seed=0,
        success=False,
        conditions={"robot_on_sofa": False},
        calls=[walk, refused, query, walk_back],
        sim_time=6.0,
    )
    assert [line.text for line in caption_at(rollout, 0.5)] == ["walk_to_position([1.00, 0.00, 0.00])"]
    during = [line.text for line in caption_at(rollout, 1.5)]
    assert during == ["climb_to_position refused: step too high", "walk_to_position([0.00, 0.00, 0.00])"]
    assert caption_at(rollout, 1.5)[0].colour != caption_at(rollout, 0.5)[0].colour
    assert [line.text for line in caption_at(rollout, 1.2 + MARK_S + 0.1)] == ["walk_to_position([0.00, 0.00, 0.00])"]
    assert [line.text for line in caption_at(rollout, 6.5)] == ["goal not reached: robot_on_sofa false"]
    won = rollout.model_copy(update={"success": True, "conditions": {"robot_on_sofa": True}})
    assert [line.text for line in caption_at(won, 6.0)] == ["goal reached: robot_on_sofa"]
    broke = rollout.model_copy(update={"conditions": {"vase_low": True, "vase_unbroken": False},
                                       "events": [VASE_BROKE]})
    assert "vase broke in a fall of 0.62 m" in [line.text for line in caption_at(broke, 7.0)]


def test_end_lines_leave_out_the_missed_goal_when_the_caption_says_it_already() -> None:
    failed = Rollout(world=0, seed=0, success=False, conditions={"vase_low": True, "vase_unbroken": False},
                     events=[VASE_BROKE], error="NameError: x")
    told = [line.text for line in end_lines(failed)]
    assert told == ["world failed: NameError: x", "vase broke in a fall of 0.62 m",
                    "goal not reached: vase_unbroken false"]
    assert [line.text for line in end_lines(failed, goal_missed=False)] == told[:2]


def test_video_paths_name_each_world_when_there_are_several() -> None:
    assert video_paths(Path("out/run.mp4"), [2]) == {2: Path("out/run.mp4")}
    assert video_paths(Path("out/run.mp4"), [0, 2]) == {0: Path("out/run-world0.mp4"), 2: Path("out/run-world2.mp4")}


@pytest.mark.slow
def test_run_command_writes_the_chosen_world_video(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.mp4"
    args = ["run", "sofa_traversing", str(program_path("sofa_traversing_direct")), "--backend", "mujoco"]
    assert status([*args, "--worlds", "2", "--video", str(out), "--video-worlds", "1"]) == 1
    assert f"wrote {out}" in capsys.readouterr().out
    with av.open(str(out)) as container:
        stream = container.streams.video[0]
        assert (stream.width, stream.height) == VIDEO_SIZE
        assert stream.frames > 2 * 30  # at least the 2 s the end is held
    assert status([*args, "--video", str(out), "--video-worlds", "1"]) == 2
    assert status([*args, "--video", str(tmp_path / "run.avi")]) == 2
    assert status([*args, "--video-worlds", "0"]) == 2
    assert status([*args, "--video", "/proc/robotool-run.mp4"]) == 2
    err = capsys.readouterr().err
    assert "only worlds 0..0 run" in err and "must name an .mp4 file" in err and "goes with --video" in err
    assert "cannot write /proc/robotool-run.mp4" in err


def test_plan_draws_footprints_path_and_the_refusal_where_the_robot_stopped(sim_scene, run_texts) -> None:
    rollout, recorder = _refused_rollout(run_texts)
    task = tasks.load("sofa_traversing")
    fig = plan_figure(task, rollout, scene=sim_scene("sofa_traversing"), track=recorder.tracks[0])
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    for obj in task.objects:
        assert any(t.startswith(obj.name) for t in texts), obj.name
    assert any(t.startswith("refused: ") and "gap" in t for t in texts)
    path = next(line for line in ax.lines if line.get_label() == "robot path (simulated)")
    end = np.array([path.get_xdata()[-1], path.get_ydata()[-1]])
    cross = next(line for line in ax.lines if line.get_marker() == "x")
    assert np.allclose([cross.get_xdata()[0], cross.get_ydata()[0]], end, atol=0.02)
    assert end[0] < task.object("sofa_2").center[0] - 0.4, "the robot stopped before the gap"


def test_plan_draws_a_push_from_the_object_and_works_without_a_recording(tmp_path: Path) -> None:
    task = tasks.load("cube_lifting")
    chair = task.object("chair")
    push = SkillCall(skill="push_to_position", args=["chair", [1.0, -0.5, 0.0]], outcome="done", started=0, ended=3)
    walk = SkillCall(
        skill="walk_to_position", args=[[2.0, -0.6, 0.0]], outcome="stalled", reason="blocked", started=3, ended=6
    )
    rollout = Rollout(world=0, seed=0, success=False, calls=[push, walk], sim_time=6.0)
    fig = plan_figure(task, rollout)
    arrows = [a for a in fig.axes[0].texts if a.get_text() == "" and a.arrow_patch is not None]
    assert np.allclose(arrows[0].xyann, chair.center[:2])
    assert tuple(arrows[0].xy) == (1.0, -0.5) and tuple(arrows[1].xy) == (2.0, -0.6)
    out = write_plan(tmp_path / "plan.png", task, rollout)
    assert Image.open(out).size[0] > 400


def _evaluate_sofa_traversing(folder: Path, rollouts_of: Callable[[Task, str, int], list[Rollout]]) -> Results:
    """The evaluator on sofa_traversing with one method whose solver (a TEST FIXTURE) returns the tool-free
    program with the rollouts ``rollouts_of(task, code, seed)``."""
    from rich.console import Console

    from robotool.eval import EvalConfig, Settings, evaluate
    from robotool.solution import Candidate, Solution

    def walks_into_the_gap(task: Task, *, seed: int, run: int) -> Solution:
        code = program("sofa_traversing_direct")
        candidate = Candidate(index=0, code=code, rollouts=rollouts_of(task, code, seed))
        return Solution(task=task.name, method="fixture", code=code, best=0, success_rate=0.0, candidates=[candidate])

    config = EvalConfig(
        out=folder, settings=Settings(worlds=1, backend="mujoco"), tasks=["sofa_traversing"], methods=["search"]
    )
    return evaluate(config, solvers={"search": walks_into_the_gap}, console=Console(quiet=True))


def test_evaluation_report_embeds_scenes_and_a_failed_world(tmp_path: Path) -> None:
    from robotool.execute import run as run_program

    folder = tmp_path / "out"
    results = _evaluate_sofa_traversing(
        folder, lambda task, code, seed: run_program(task, code, worlds=1, seed=seed, backend="mujoco").rollouts
    )
    kinds = [(p.kind, p.failure_class) for p in results.pictures]
    assert kinds[0] == ("scene", None) and kinds[1][0] == "failure" and len(kinds) == 2
    failure = results.pictures[1]
    assert failure.run.startswith("sofa_traversing/search/0@") and failure.world == 0 and "gap" in failure.caption
    assert failure.reproduced is True
    report = (folder / "report.md").read_text()
    saved = json.loads((folder / "results.json").read_text())
    for picture in results.pictures:
        assert (folder / picture.file).is_file()
        assert f"({picture.file})" in report
    assert [p["file"] for p in saved["pictures"]] == [p.file for p in results.pictures]
    still = np.asarray(Image.open(folder / failure.file).convert("RGB"))
    assert _hue_pixels(still, ROBOT_RGBA).sum() > 20


def test_evaluation_picture_says_when_the_world_did_not_fail_the_same_way_again(tmp_path: Path) -> None:
    def claimed(task: Task, code: str, seed: int) -> list[Rollout]:  # TEST FIXTURE: not what this program does
        stall = SkillCall(skill="walk_to_position", args=[[2.0, 0.0, 0.0]], outcome="stalled", reason="blocked")
        return [Rollout(world=0, seed=seed, success=False, conditions={"robot_on_sofa_2": False}, calls=[stall])]

    results = _evaluate_sofa_traversing(tmp_path / "out", claimed)
    failure = results.pictures[1]
    assert "stalled: blocked" in failure.caption and failure.reproduced is False


def test_solve_command_films_the_best_program(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "videos"
    args = ["solve", "milk_reaching_near", "--planner", "search", "--worlds", "1", "--backend", "mujoco"]
    assert status([*args, "--video", str(folder)]) == 0
    out = folder / "milk_reaching_near-world0.mp4"
    assert f"wrote {out}" in capsys.readouterr().out
    with av.open(str(out)) as container:
        assert container.streams.video[0].frames > 2 * 30
    assert status([*args, "--video", str(out)]) == 2  # a file, not a folder
    assert status([*args, "--video", str(folder), "--video-worlds", "1"]) == 2
    err = capsys.readouterr().err
    assert "is a file, not a folder" in err and "only worlds 0..0 run" in err


def test_frames_between_ticks_interpolate_the_recorded_positions(sim_scene) -> None:
    from robotool.render.video import _Interpolator
    from robotool.sim.recorder import Track

    scene = sim_scene("cube_lifting")
    model = scene.model
    start = model.qpos0.copy()
    moved = start.copy()
    slides = [model.jnt_qposadr[model.joint(f"robot_{axis}").id] for axis in "xy"]
    moved[slides] += [0.2, -0.1]
    free = model.jnt_qposadr[model.joint("surfboard__free").id]
    moved[free + 3 : free + 7] = [np.cos(0.5), 0.0, 0.0, np.sin(0.5)]  # the board turned to a yaw of 1 rad
    track = Track(times=[0.0, 0.1], qpos=[start, moved], mocap_pos=[np.zeros((0, 3))] * 2)
    states = _Interpolator(model, track)
    assert np.array_equal(states.at(0.0)[0], start) and np.array_equal(states.at(0.3)[0], moved)
    middle = states.at(0.05)[0]
    assert np.allclose(middle[slides], (start[slides] + moved[slides]) / 2)

    def angle(a: np.ndarray, b: np.ndarray) -> float:
        return float(2 * np.arccos(min(1.0, abs(a @ b))))

    quats = [q[free + 3 : free + 7] for q in (start, middle, moved)]
    assert np.isclose(np.linalg.norm(quats[1]), 1.0)
    assert np.isclose(angle(quats[0], quats[1]), angle(quats[0], quats[2]) / 2)
    assert np.isclose(angle(quats[1], quats[2]), angle(quats[0], quats[2]) / 2)


def test_videos_fall_back_to_mpeg4_without_an_h264_encoder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import robotool.render.video as video
    from robotool.render.painter import RenderError

    assert video._encoder({"mpeg4", "libx264"}) == "libx264" and video._encoder({"mpeg4"}) == "mpeg4"
    with pytest.raises(RenderError, match="none of the video encoders"):
        video._encoder({"gif"})
    monkeypatch.setattr(video, "ENCODERS", ("mpeg4",))
    frames = (np.full((VIDEO[1], VIDEO[0], 3), 40 * k, dtype=np.uint8) for k in range(5))
    assert video.write_mp4(tmp_path / "m.mp4", frames, fps=FPS, width=VIDEO[0], height=VIDEO[1]) == 5
    with av.open(str(tmp_path / "m.mp4")) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name == "mpeg4" and sum(1 for _ in container.decode(stream)) == 5


def test_evaluation_picture_replays_a_later_candidates_world_from_its_recorded_seed(tmp_path: Path) -> None:
    # The chosen candidate ran second in its batch, so its world is numbered 1 while it was perturbed from the
    # run's seed 0: the picture must replay that seed (once reconstructed as index - seed = -1, a crash).
    from robotool.verify import run_codes

    results = _evaluate_sofa_traversing(
        tmp_path / "out",
        lambda task, code, seed: run_codes(task, [code, code], worlds=1, seed=seed, backend="mujoco")[1],
    )
    failure = results.pictures[1]
    assert failure.world == 1 and failure.reproduced is True


@pytest.mark.slow  # two planner runs, then their pictures drawn twice (in pool processes, then here)
def test_evaluation_pictures_drawn_in_two_processes_are_those_drawn_in_one(tmp_path: Path) -> None:
    # The evaluator draws each instance in a pool process as soon as its last run is recorded, while the other
    # runs go on (in their own pool): the pictures are those drawn one by one afterwards, in instance order.
    from rich.console import Console

    from robotool.eval import EvalConfig, Settings, evaluate
    from robotool.eval.executor import LocalExecutor
    from robotool.eval.instances import select
    from robotool.eval.pictures import write_pictures

    names = ["milk_reaching", "sofa_traversing"]
    config = EvalConfig(
        out=tmp_path / "2", settings=Settings(worlds=1, backend="mujoco"), tasks=names, methods=["no_tool"]
    )
    results = evaluate(config, console=Console(quiet=True), executor=LocalExecutor(1, processes=2))
    instances, _ = select(names, None, None)
    one, two = write_pictures(instances, results.records, tmp_path / "1", "mujoco", processes=1), results.pictures
    assert [p.model_dump() for p in one] == [p.model_dump() for p in two]
    assert [p.kind for p in two].count("failure") >= 2 and all(p.reproduced is not False for p in two)
    for picture in two:
        assert (tmp_path / "2" / picture.file).is_file()


def test_plan_labels_never_overlap_and_moved_things_are_drawn_where_they_ended() -> None:
    """On sofa_traversing the push's and the walk's labels were drawn over each other."""
    import itertools

    task = tasks.load("sofa_traversing")
    push = SkillCall(skill="push_to_position", args=["surfboard", [0.85, 0.0, 0.38]], outcome="done", ended=3)
    walk = SkillCall(skill="walk_to_position", args=[[1.775, 0.0, 0.17]], outcome="done", started=3, ended=8)
    fig = plan_figure(task, Rollout(world=0, seed=0, success=True, calls=[push, walk], sim_time=8.0))
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    labels = [t for t in ax.texts if t.get_text()]
    assert {"1. push_to_position", "2. walk_to_position", "surfboard (end)"} <= {t.get_text() for t in labels}
    for a, b in itertools.combinations(labels, 2):
        assert not a.get_window_extent(renderer).overlaps(b.get_window_extent(renderer)), (a.get_text(), b.get_text())
    board = next(t for t in labels if t.get_text() == "surfboard (end)")
    assert tuple(board.xy) == (0.85, 0.0)
    assert "robot end" in ax.get_legend_handles_labels()[1]
