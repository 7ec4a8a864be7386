"""One thing wrong with a task file (:class:`Problem`), as the task-file checks and each robot's checks report it."""

from __future__ import annotations

from pydantic import BaseModel


class Problem(BaseModel):
    """One thing wrong with a task file, at a field path such as ``objects[2].size[0]``."""

    path: str
    message: str

    def __str__(self) -> str:
        return f"{self.path}: {self.message}" if self.path else self.message
