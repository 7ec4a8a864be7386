"""Built-in task files, the task registry and the procedural task families.

``names()`` lists the built-in tasks; ``load(name_or_path)`` returns a validated :class:`Task`
for a built-in name or for a path to a YAML/JSON task file. ``families()`` and
``generate(family, seed)`` give seeded variations (see :mod:`robotool.tasks.families`).
"""

from __future__ import annotations

from robotool.tasks.builtin import load, names, source
from robotool.tasks.families import (
    Instance,
    families,
    generate,
    register_family,
    registered_families,
    write_instance,
)

__all__ = [
    "Instance",
    "families",
    "generate",
    "load",
    "names",
    "register_family",
    "registered_families",
    "source",
    "write_instance",
]
