"""Render the page: Jinja2 with autoescape on, and every value printed through the ``html`` sink's escaper
(:func:`robotool.safe_text.html_text`: controls made visible, length capped, HTML escaped; a program is listed
whole, so that all that runs shows: the sandbox and the reply extractor refuse one over 100 KB before it gets here); the
CSS is inlined so the page is one file, and pictures and videos are linked by relative paths (an evaluation) or embedded
as ``data:`` URIs (a single solve or run)."""

from __future__ import annotations

import base64
import os
import tempfile
from collections.abc import Mapping, Sequence
from functools import cache
from importlib.resources import files
from pathlib import Path

from jinja2 import Environment, PackageLoader, select_autoescape
from markupsafe import Markup, escape

from robotool.eval.records import Results
from robotool.eval.report import preamble
from robotool.eval.tables import TextTable
from robotool.execute import RunReport
from robotool.report_page.views import Media, PageView, record_view, rollouts_view, solution_view
from robotool.safe_text import html_text, url_path
from robotool.solution import Solution
from robotool.task.task_model import Task


def _finalize(value: object) -> Markup:
    """Every ``{{ value }}`` on the page goes through the sink's escaper (None prints nothing)."""
    if isinstance(value, Markup):
        return value
    return Markup(html_text("" if value is None else str(value)))


def _url(src: str) -> Markup:
    """A media address the host built: a ``data:`` URI, HTML-escaped whole (the sink's length cap would cut it), or a
    path relative to the page (its file name may be the user's, control characters and all), percent-encoded."""
    return escape(src if src.startswith("data:") else url_path(src))


@cache
def _environment() -> Environment:
    env = Environment(
        loader=PackageLoader("robotool.report_page", "templates"),
        autoescape=select_autoescape(default=True, default_for_string=True),
        finalize=_finalize,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["url"] = _url
    env.filters["program"] = lambda code: Markup(html_text(code, len(code)))  # whole: all that runs shows
    env.filters["percent"] = lambda rate: "–" if rate is None else f"{100 * rate:.0f}%"
    return env


def _css() -> Markup:
    """The stylesheet shipped in the package; host text, inlined so that the page is one file."""
    return Markup(files("robotool.report_page").joinpath("static/report.css").read_text(encoding="utf-8"))


def render(page: PageView) -> str:
    """The HTML of ``page``."""
    return _environment().get_template("report.html.j2").render(page=page, css=_css())


def evaluation_page(results: Results, tables: Sequence[TextTable], plots: Sequence[str]) -> str:
    """``report.html`` of an evaluation folder: media linked by their paths in the folder."""
    page = PageView(
        title="robotool evaluation",
        preamble=[line.removeprefix("- ") for line in preamble(results, escape=str)],
        tables=list(tables),
        plots=[Media(src=name, caption=name) for name in plots],
        runs=[record_view(r, results.pictures, results.videos) for r in results.records],
    )
    return render(page)


def embedded(path: Path, mime: str, caption: str) -> Media:
    """A picture as a ``data:`` URI, so that a single page carries it."""
    return Media(src=f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode("ascii"), caption=caption)


def linked(path: Path, page: Path, caption: str = "") -> Media:
    """A file linked from ``page`` by its path relative to the page's folder."""
    rel = os.path.relpath(path.resolve(), page.resolve().parent)
    return Media(src=Path(rel).as_posix(), caption=caption or path.name)


def _scene(task: Task) -> tuple[Media | None, list[str]]:
    """The task's scene at its start, drawn and embedded; or no picture and a note saying why."""
    from robotool.errors import RobotoolError
    from robotool.render.still import render_scene

    with tempfile.TemporaryDirectory() as folder:
        try:
            path = render_scene(task, Path(folder) / f"{task.name}.png", width=640, height=360)
        except (RobotoolError, ImportError) as e:
            return None, [f"no scene picture: {e}"]
        return embedded(path, "image/png", f"{task.name}: the scene at the start"), []


def _videos(page: Path, videos: Mapping[int, Path]) -> dict[int, Media]:
    return {w: linked(path, page, f"world {w}") for w, path in videos.items()}


def solution_page(page: Path, task: Task, solution: Solution, videos: Mapping[int, Path]) -> str:
    """The page of one solve, to be written at ``page``: the stages, every candidate, the chosen one's worlds
    (``videos``: world -> its MP4, linked relative to the page) and the repairs; the scene embedded."""
    from robotool.eval.grading import grade
    from robotool.task.concepts import key_concepts

    concepts = grade(key_concepts(task), solution.stages.key_concepts)
    scene, notes = _scene(task)
    view = solution_view(solution, scene, concepts, _videos(page, videos))
    view.notes = [*view.notes, *notes]
    return render(PageView(title=f"robotool solve: {task.name}", runs=[view]))


def run_page(page: Path, task: Task, report: RunReport, videos: Mapping[int, Path]) -> str:
    """The page of one ``robotool run``, to be written at ``page``: the program and its worlds."""
    scene, notes = _scene(task)
    view = rollouts_view(task.name, report.code, report.rollouts, scene, _videos(page, videos))
    view.notes = notes
    return render(PageView(title=f"robotool run: {task.name}", runs=[view]))
