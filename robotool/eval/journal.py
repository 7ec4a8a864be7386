"""The journal that makes an evaluation resumable: one fsynced JSON line per finished run.

A run is appended only when it has finished, as a single ``write`` of one line followed by
``fsync``, so a kill at any moment loses at most the runs in flight. Reading tolerates a torn last
line (a kill mid-write): it is cut off before the next append. A key already in the journal is
never appended again, so every run is recorded exactly once however often the command restarts.
Final files are written atomically (a temporary file, fsynced, then renamed over the target).
"""

from __future__ import annotations

import os
import threading
from pathlib import Path

from robotool.eval.config import EvalError
from robotool.eval.records import RunRecord
from robotool.safe_text import json_text

JOURNAL = "journal.jsonl"


class Journal:
    """The finished runs of one output folder, appendable from any thread."""

    def __init__(self, folder: Path):
        self.path = folder / JOURNAL
        self._lock = threading.Lock()
        self.records: dict[str, RunRecord] = {}
        folder.mkdir(parents=True, exist_ok=True)
        self._load()

    def _load(self) -> None:
        """Read every line; cut a torn last line so that the next append starts on a fresh line."""
        if not self.path.exists():
            return
        data = self.path.read_bytes()
        lines = data.splitlines(keepends=True)
        good = 0
        for number, line in enumerate(lines, start=1):
            try:
                if not line.endswith(b"\n"):
                    raise ValueError("no line end")
                record = RunRecord.model_validate_json(line)
            except ValueError:  # pydantic.ValidationError included
                if number == len(lines):
                    break  # torn by a kill mid-write
                raise EvalError(f"{self.path} line {number} is not a run record; use another --out") from None
            self.records.setdefault(record.key.id, record)
            good += len(line)
        if good < len(data):
            with self.path.open("r+b") as f:
                f.truncate(good)
                os.fsync(f.fileno())

    def __contains__(self, key_id: str) -> bool:
        return key_id in self.records

    def append(self, record: RunRecord) -> bool:
        """Record a finished run durably; False (and nothing written) when its key is already there."""
        line = (json_text(record) + "\n").encode()
        with self._lock:
            if record.key.id in self.records:
                return False
            with self.path.open("ab") as f:
                f.write(line)
                f.flush()
                os.fsync(f.fileno())
            self.records[record.key.id] = record
            return True


def write_atomic(path: Path, text: str) -> None:
    """Replace ``path`` with ``text`` so that readers see the old file or the new one, never a part."""
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
