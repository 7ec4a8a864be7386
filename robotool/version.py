"""The installed robotool version, for ``--version`` and for the evaluator's run identity."""

from __future__ import annotations

from importlib import metadata


def version() -> str:
    """The installed robotool version (``unknown`` when it runs from a bare source tree)."""
    try:
        return metadata.version("robotool")
    except metadata.PackageNotFoundError:
        return "unknown"
