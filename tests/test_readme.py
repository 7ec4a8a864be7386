"""The README and docs are executable: every shell command and Python snippet in them runs here, as written.

Each command of a ``bash`` block (and each ``python`` block) is one test, run in order in one scratch folder
that holds the repository's ``examples/`` and ``docs/`` and the README's skill program saved under the name the
README gives it (``save it as `my_program.py```). A command must exit 0, or 1 where the README documents 1 as
a result (``robotool run``: a world missed the goal), with no traceback. What cannot run here is skipped by
name, with the reason: commands tagged in the README ``(needs a model provider)`` or ``(needs a Ray
cluster)``, ``pip install`` lines, and the quick start, which ``.ci/run`` runs as written. Commands that take
long are shrunk only by documented flags (``SHRUNK``). A README change that breaks a command fails here.
"""

from __future__ import annotations

import os
import re
import shlex
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
TAGS = {
    "(needs a model provider)": "needs a real language-model provider and its key (no network here)",
    "(needs a Ray cluster)": "needs a Ray cluster to join (none here)",
}
SHRUNK = {  # command prefix -> documented flags appended to keep the suite fast
    "python -m robotool.eval --executor ray": "--tasks milk_reaching_near --methods no_tool --out results/ray",
}
RESULT_EXIT = {"robotool run": {0, 1}}  # documented: 1 when a world missed the goal
SLOW = ("robotool optimize", "robotool solve", "robotool.eval", "robotool eval", "--video")  # 8-42 s: marked slow
TIMEOUT_S = 300


@dataclass(frozen=True)
class Snippet:
    """One command of a bash block, or one python block, with where it stands."""

    document: str
    line: int
    language: str  # "bash" or "python"
    text: str
    background: bool = False
    block: int = 0  # the first line of its block

    @property
    def id(self) -> str:
        first = self.text.splitlines()[0]
        head = " ".join(first.split("#")[0].split()) if self.language == "bash" else f"python block: {first}"
        return f"{self.document}:{self.line}: {head[:80]}"


def _blocks(path: Path) -> Iterator[tuple[int, str, str, str]]:
    """(first line, language, body, the prose just before) of each fenced block."""
    text = path.read_text(encoding="utf-8")
    for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.DOTALL | re.MULTILINE):
        before = text[: m.start()]
        yield before.count("\n") + 2, m.group(1), m.group(2), before[-400:]


def _commands(body: str, first_line: int) -> Iterator[tuple[int, str]]:
    """The commands of a bash block, continuation lines joined and comment lines dropped."""
    pending: list[str] = []
    start = first_line
    for k, line in enumerate(body.splitlines()):
        if not pending:
            start = first_line + k
            if not line.strip() or line.lstrip().startswith("#"):
                continue
        pending.append(line.rstrip())
        if not line.rstrip().endswith("\\"):
            yield start, "\n".join(pending)
            pending = []


def saved_programs() -> dict[str, str]:
    """The README's skill programs that it asks to save under a name: file name -> program."""
    programs: dict[str, str] = {}
    for path in DOCUMENTS:
        for _, language, body, before in _blocks(path):
            named = re.search(r"save it as `([\w.]+\.py)`[^`]*$", before)
            if language == "python" and named:
                programs[named.group(1)] = body
    return programs


def snippets() -> list[Snippet]:
    """Every bash command and host-Python block of the README and docs, in order."""
    found: list[Snippet] = []
    programs = saved_programs()
    for path in DOCUMENTS:
        name = path.relative_to(ROOT).as_posix()
        for line, language, body, _ in _blocks(path):
            if language == "bash":
                for start, command in _commands(body, line):
                    background = command.split("#")[0].rstrip().endswith("&")
                    found.append(Snippet(name, start, "bash", command, background, line))
            elif language == "python" and body not in programs.values():
                found.append(Snippet(name, line, "python", body, block=line))
    return found


def _quick_start() -> list[str]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Quick start\s+```bash\n(.*?)```", readme, re.DOTALL)
    assert block is not None, "README has no quick start block"
    return block.group(1).strip().splitlines()


def skip_reason(snippet: Snippet) -> str | None:
    """Why ``snippet`` is not run here, or None when it runs."""
    for tag, why in TAGS.items():
        if tag in snippet.text:
            return why
    if snippet.language == "bash" and snippet.text in _quick_start():
        return "the quick start: .ci/run runs it as written, in a new virtual environment"
    if snippet.language == "bash" and snippet.text.startswith("pip install"):
        return "installs packages: .ci/run installs the dev extra, which includes it"
    return None


class Scratch:
    """The scratch folder the snippets run in, and the background processes they started."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.background: list[subprocess.Popen[bytes]] = []
        for shared in ("examples", "docs"):
            (folder / shared).symlink_to(ROOT / shared)
        for name, program in saved_programs().items():
            (folder / name).write_text(program, encoding="utf-8")
        bin_dir = str(Path(sys.executable).parent)
        self.env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"}
        self.env.pop("ROBOTOOL_LM", None)

    def stop(self) -> None:
        for process in self.background:
            process.terminate()
            process.wait(timeout=30)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Scratch]:
    folder = Scratch(tmp_path_factory.mktemp("readme"))
    yield folder
    folder.stop()


def _wait_for_port(command: str, process: subprocess.Popen[bytes]) -> None:
    """Wait until the server a background command started answers on its ``--port`` (as a user would)."""
    port = re.search(r"--port (\d+)", command)
    if port is None:
        return
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        assert process.poll() is None, f"{command!r} ended with status {process.returncode}"
        try:
            socket.create_connection(("127.0.0.1", int(port.group(1))), timeout=1).close()
            return
        except OSError:
            time.sleep(0.2)
    raise AssertionError(f"{command!r} did not answer on port {port.group(1)} within 60 s")


def _command_line(snippet: Snippet) -> str:
    command = snippet.text
    for prefix, flags in SHRUNK.items():
        if command.split("#")[0].strip() == prefix or command.startswith(prefix + " "):
            head = command.partition("#")[0]
            command = f"{head.rstrip()} {flags}"
    return command


def _params() -> list[object]:
    """One test per snippet; a block that starts a background server keeps its commands on one worker, in order;
    commands that search, evaluate or draw a video are marked slow."""
    found = snippets()
    serving = {(s.document, s.block) for s in found if s.background}
    return [
        pytest.param(
            s,
            id=s.id,
            marks=[pytest.mark.xdist_group(f"{s.document}:{s.block}")] * ((s.document, s.block) in serving)
            + [pytest.mark.slow] * any(word in s.text for word in SLOW),
        )
        for s in found
    ]


@pytest.mark.parametrize("snippet", _params())
def test_readme_snippet_runs_as_written(snippet: Snippet, scratch: Scratch) -> None:
    if (why := skip_reason(snippet)) is not None:
        pytest.skip(why)
    if snippet.language == "python":
        argv = [sys.executable, "-c", snippet.text]
        accepted = {0}
    else:
        command = _command_line(snippet)
        if snippet.background:
            process = subprocess.Popen(
                ["bash", "-c", command.split("#")[0].rstrip().removesuffix("&")],
                cwd=scratch.folder, env=scratch.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )
            scratch.background.append(process)
            _wait_for_port(command, process)
            return
        argv = ["bash", "-o", "pipefail", "-c", command]
        program = shlex.split(command, comments=True)[:2]
        accepted = RESULT_EXIT.get(" ".join(program), {0})
    done = subprocess.run(argv, cwd=scratch.folder, env=scratch.env, capture_output=True, text=True,
                          timeout=TIMEOUT_S, check=False)
    said = f"{snippet.id}\nexit {done.returncode}\n--- stdout\n{done.stdout[-3000:]}\n--- stderr\n{done.stderr[-3000:]}"
    assert done.returncode in accepted, said
    assert "Traceback" not in done.stdout + done.stderr, said


def test_every_tag_and_shrink_still_matches_a_command() -> None:
    texts = [s.text for s in snippets()]
    for tag in TAGS:
        assert any(tag in t for t in texts), f"no README command is tagged {tag}: drop it from TAGS"
    for prefix in SHRUNK:
        assert any(t.startswith(prefix) for t in texts), f"no README command starts with {prefix!r}"


def test_the_readme_names_the_program_its_commands_run() -> None:
    assert "my_program.py" in saved_programs()


def test_the_readme_lists_the_optimisable_predictors_as_they_are() -> None:
    from robotool.program.lm_program import Proposer

    readme = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    said = r"while an optimiser runs, its `named_predictors\(\)` are exactly (.*?): the Repair stage"
    claim = re.search(said, readme)
    assert claim is not None, "the README no longer says which predictors an optimiser compiles"
    program = Proposer()
    program.repair_frozen = True  # as robotool optimize sets it
    assert re.findall(r"`(\w+)`", claim.group(1)) == [name for name, _ in program.named_predictors()]
