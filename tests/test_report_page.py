"""report.html: the page of an evaluation and of a single solve or run, written offline and opened in headless
Chromium (Debian's ``chromium`` and ``chromium-driver``, driven by Selenium).

One small evaluation (sofa_traversing, one method whose solver is a TEST FIXTURE returning a program that walks
into the gap, prints a hostile string and carries a hostile comment; one world, filmed) is shared by the tests of
this module through a module-scoped fixture; the browser tests share one browser.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from fixtures.reference import program

from robotool import tasks
from robotool.cli import main
from robotool.eval.records import Results
from robotool.signatures.traces import FailureTrace
from robotool.solution import Candidate, CandidateFailure, RepairAttempt, RepairRound, Solution
from robotool.task.task_model import Task

pytestmark = [pytest.mark.xdist_group("html"), pytest.mark.slow]  # a shared evaluation, a browser: 10-13 s each

SCRIPT = "<script>alert(1)</script>"
IMG = "<img src=x onerror=\"document.title='pwned'\">"
NOTE = "<b onmouseover=alert(3)>a note a model wrote</b>"
HOSTILE_CODE = f"# {SCRIPT}\nprint({IMG!r})\n"
"""A program's hostile text: a comment (shown with the code) and what it prints (shown with its world)."""


def _hostile_solver(task: Task, *, seed: int, run: int) -> Solution:
    """TEST FIXTURE: the tool-free program with a hostile comment and output; it walks into the gap and fails."""
    from robotool.execute import run as run_program

    code = HOSTILE_CODE + program("sofa_traversing_direct")
    rollouts = run_program(task, code, worlds=1, seed=seed, backend="mujoco").rollouts
    candidate = Candidate(index=0, code=code, rollouts=rollouts)
    return Solution(
        task=task.name, method="fixture", code=code, best=0, success_rate=0.0, candidates=[candidate], notes=[NOTE]
    )


@pytest.fixture(scope="module")
def evaluation(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Results]:
    """The results folder of a one-run evaluation with pictures and one video (module-scoped: shared)."""
    from rich.console import Console

    from robotool.eval import EvalConfig, Settings, evaluate

    folder = tmp_path_factory.mktemp("evaluation")
    config = EvalConfig(
        out=folder,
        settings=Settings(worlds=1, backend="mujoco"),
        tasks=["sofa_traversing"],
        methods=["search"],
        videos=1,
    )
    results = evaluate(config, solvers={"search": _hostile_solver}, console=Console(quiet=True))
    return folder, results


def test_the_evaluation_folder_holds_a_small_self_contained_page(evaluation: tuple[Path, Results]) -> None:
    folder, results = evaluation
    page = folder / "report.html"
    text = page.read_text(encoding="utf-8")
    assert page.stat().st_size < 2_000_000
    assert "http://" not in text and "https://" not in text  # nothing to fetch from a network
    [video] = results.videos
    assert video.world == 0 and (folder / video.file).stat().st_size > 1000 and video.plan is not None
    for file in [*(p.file for p in results.pictures), video.file, video.plan]:
        assert f'src="{file}"' in text and (folder / file).is_file()
    for plot in ("success.png", "errors.png", "discrimination.png"):
        assert f'src="{plot}"' in text and (folder / plot).is_file()
    assert "<script" not in text and "<img src=x" not in text and "<b onmouseover" not in text
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in text


def test_videos_film_the_first_n_failed_worlds_of_each_method_that_ran_a_program() -> None:
    from robotool.eval.recordings import failed_worlds
    from robotool.eval.records import RunKey, RunRecord, WorldResult

    def record(method: str, run: int, failed: list[int], code: str | None = "x = 1") -> RunRecord:
        worlds = [WorldResult(world=w, seed=100 + w, success=w not in failed) for w in range(3)]
        key = RunKey(task="t", method=method, run=run)
        return RunRecord(
            key=key, embodiment="arm", needs_tool=False, world_seed=0, success_rate=0, worlds=worlds, code=code
        )

    records = [record("a", 0, [], None), record("a", 1, [1, 2]), record("b", 0, [0]), record("a", 2, [0])]
    chosen = [(r.key.method, r.key.run, world, seed) for r, world, seed in failed_worlds(records, 2)]
    assert chosen == [("a", 1, 1, 101), ("a", 1, 2, 102), ("b", 0, 0, 100)]
    assert failed_worlds(records, 0) == []


def test_the_pages_escaper_makes_controls_visible_caps_the_length_and_links_videos(tmp_path: Path) -> None:
    """Every value on the page goes through the html sink's escaper, not only through autoescape. A program is
    listed whole (found by an adversarial run: a listing cut at 4000 characters hid the calls after the cut, which
    ran); other text is cut at the sink's cap, saying how much it left out."""
    from robotool.execute import RunReport
    from robotool.report_page.page import run_page
    from robotool.rollout import Rollout

    task = tasks.load("sofa_traversing")
    report_code = "print('x')\n# \x1b]52;c;eA==\x07 \u202egnp.exe\n" + "y = 1\n" * 2000

    report = RunReport(
        task=task.name,
        worlds=1,
        seed=0,
        backend="mujoco",
        success=False,
        success_rate=0.0,
        code=report_code,
        rollouts=[Rollout(world=0, seed=0, success=False, output="\x1b[2J" * 5000)],
    )
    text = run_page(tmp_path / "page" / "run.html", task, report, {0: tmp_path / "media" / "run.mp4"})
    assert 'src="../media/run.mp4"' in text  # a video is linked relative to the page
    assert "\x1b" not in text and "\u202e" not in text
    assert "\\x1b]52;c;eA==\\x07" in text and "\\u202egnp.exe" in text
    assert "y = 1\ny = 1" in text and text.count("y = 1") == 2000  # the program whole: all that runs shows
    assert "\\x1b[2J" * 100 in text and "… (20000 characters in all)" in text  # the output cut, saying so


def test_run_writes_a_page_with_the_scene_and_the_trace(tmp_path: Path) -> None:
    code, page = tmp_path / "P.py", tmp_path / "run.html"
    code.write_text(HOSTILE_CODE + program("sofa_traversing_direct"), encoding="utf-8")
    assert main(["run", "sofa_traversing", str(code), "--backend", "mujoco", "--html", str(page)]) == 1
    text = page.read_text(encoding="utf-8")
    assert 'src="data:image/png;base64,' in text  # the scene travels with the page
    assert "refused" in text and "gap" in text
    assert "&lt;script&gt;" in text and "<script" not in text


def _solution_with_a_repair() -> Solution:
    """TEST FIXTURE: two candidates, the second repaired from the first, a hostile diagnosis; no simulation."""
    from robotool.rollout import Rollout, SkillCall

    refused = SkillCall(skill="walk_to_position", args=[[2.0, 0.0, 0.0]], outcome="refused", reason="gap of 0.30 m")
    failed = Rollout(world=0, seed=7, success=False, calls=[refused], error="refused")
    first = Candidate(
        index=0,
        code="walk_to_position([2.0, 0.0, 0.0])\n",
        rollouts=[failed],
        failure=CandidateFailure(stage="simulation", kind="worlds_failed", reason="gap", failed_worlds=1, worlds=1),
    )
    second = Candidate(index=1, code="# repaired\n", rollouts=[Rollout(world=0, seed=7, success=True)], repaired_from=0)
    trace = FailureTrace(worlds=1, failed_worlds=1, world=0, calls=[], error=None, scope="plan")
    attempt = RepairAttempt(source=0, candidate=1, shown=trace, scope="plan", diagnosis=SCRIPT, success_rate=1.0)
    return Solution(
        task="sofa_traversing",
        method="robotool",
        code=second.code,
        best=1,
        success_rate=1.0,
        candidates=[first, second],
        repairs=[RepairRound(round=1, attempts=[attempt])],
    )


def test_solve_writes_a_page_with_every_candidate_and_the_repair(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import robotool.planner

    monkeypatch.setattr(robotool.planner, "solve", lambda task, **_: _solution_with_a_repair())  # TEST FIXTURE
    page = tmp_path / "solve.html"
    assert main(["solve", "sofa_traversing", "--planner", "search", "--html", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert "candidate 1 (chosen), repaired from candidate 0" in text
    assert "walk_to_position([2.0, 0.0, 0.0])" in text  # the failed candidate's program, in its drill-down
    assert "round 1" in text and "diagnosis: &lt;script&gt;alert(1)&lt;/script&gt;" in text
    assert "<td>ground truth</td>" in text and "(missed)" not in text  # no Analyzer ran: nothing was graded


def test_solve_writes_a_page_for_candidates_whose_calls_were_not_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A search keeps the skill calls of its best few failed candidates only; the others' events still name their
    calls by number, and the page says which (it raised IndexError on such a candidate)."""
    import robotool.planner
    from robotool.rollout import Event, Rollout

    solution = _solution_with_a_repair()
    refusal = Event(kind="refused", call=3, detail="the way is blocked by surfboard")
    stripped = Rollout(world=0, seed=7, success=False, calls=[], events=[refusal])  # TEST FIXTURE
    solution.candidates[0].rollouts = [stripped]
    monkeypatch.setattr(robotool.planner, "solve", lambda task, **_: solution)  # TEST FIXTURE
    page = tmp_path / "solve.html"
    assert main(["solve", "sofa_traversing", "--planner", "search", "--html", str(page)]) == 0
    assert "call 4: refused" in page.read_text(encoding="utf-8")


# -- in the browser ------------------------------------------------------------------------------------------


def _browser_or_skip() -> tuple[str, str]:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if chromium is None or driver is None:
        pytest.skip("headless Chromium is not installed (Debian: apt-get install chromium chromium-driver)")
    return chromium, driver


@pytest.fixture(scope="module")
def browser(request: pytest.FixtureRequest) -> Iterator[object]:
    """Headless Chromium on the evaluation's report.html, logging the console (module-scoped: shared); skipped,
    before the evaluation runs, where Chromium or Selenium is missing."""
    chromium, driver_path = _browser_or_skip()
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (pip install selenium)")
    from selenium.webdriver.chrome.service import Service

    evaluation: tuple[Path, Results] = request.getfixturevalue("evaluation")

    options = webdriver.ChromeOptions()
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1200,900"):
        options.add_argument(argument)
    options.binary_location = chromium
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    driver.get((evaluation[0] / "report.html").as_uri())
    yield driver
    driver.quit()


def test_the_browser_shows_the_tables_and_opens_a_runs_drill_down(browser, evaluation: tuple[Path, Results]) -> None:
    folder, _ = evaluation
    titles = [line[3:] for line in (folder / "report.md").read_text().splitlines() if line.startswith("## ")]
    shown = [h.text for h in browser.find_elements("css selector", "section.table h2")]
    assert shown and shown == [t for t in titles if t != "Pictures"]
    assert all(t.find_elements("css selector", "tbody tr") for t in browser.find_elements("css selector", "table"))
    details = browser.find_element("css selector", "details.run")
    assert details.get_attribute("open") is None
    trace = details.find_element("css selector", "table.trace")
    assert not trace.is_displayed()
    browser.find_element("css selector", "table.runs-index a").click()  # the link opens the run it points to
    assert details.get_attribute("open") is not None and trace.is_displayed()
    assert "refused" in trace.text and "gap" in trace.text
    assert details.find_element("css selector", ".scene img").get_property("naturalWidth") > 0


def test_the_browser_can_play_the_recorded_video(browser) -> None:
    from selenium.webdriver.support.ui import WebDriverWait

    video = browser.find_element("css selector", "video")
    ready = WebDriverWait(browser, 20).until(
        lambda d: d.execute_script("const v = arguments[0]; return v.readyState >= 1 && v.duration > 0;", video)
    )
    assert ready
    assert browser.execute_script("return arguments[0].error", video) is None


def test_a_hostile_programs_text_stays_inert(browser) -> None:
    from selenium.common.exceptions import NoAlertPresentException

    browser.execute_script("document.querySelectorAll('details').forEach(d => d.open = true)")
    with pytest.raises(NoAlertPresentException):
        browser.switch_to.alert  # noqa: B018 (the property raises when no alert is open)
    assert browser.title == "robotool evaluation"
    assert not browser.find_elements("css selector", "script, img[src='x'], b[onmouseover]")
    code = browser.find_element("css selector", "pre.code").text
    assert code.startswith(f"# {SCRIPT}\nprint(")
    assert IMG in browser.find_element("css selector", "pre.output").text
    assert NOTE in browser.find_element("css selector", "details.run p.note").text


def test_the_browser_console_logs_no_errors(browser) -> None:
    browser.execute_script("document.querySelectorAll('details').forEach(d => d.open = true)")
    images = browser.find_elements("css selector", "img")
    assert images and all(i.get_property("naturalWidth") > 0 for i in images), "a picture did not load"
    errors = [entry for entry in browser.get_log("browser") if entry["level"] == "SEVERE"]
    assert not errors, errors
