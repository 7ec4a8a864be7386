"""A task file's text read as YAML or JSON (:func:`parse_text`), with every key a mapping gives more than once
(:class:`Repeated`): both parsers keep the last of them silently, and a task file gives each key once."""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Literal

import yaml

Kind = Literal["YAML", "JSON"]
Location = tuple[int | str, ...]
"""Where a value is in a file's data: the keys and list indexes that lead to it."""
MERGE_TAG = "tag:yaml.org,2002:merge"  # YAML's ``<<: *base``, whose keys a mapping may override


@dataclass(frozen=True)
class Repeated:
    """A key that one mapping of the file gives ``count`` times, on ``lines`` (YAML; JSON's parser gives none)."""

    mapping: dict[Any, Any]
    key: Any
    count: int
    lines: tuple[int, ...] = ()


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader, which also records the keys a mapping gives more than once."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self.repeated: list[Repeated] = []

    def construct_checked_map(self, node: yaml.MappingNode) -> Iterator[dict[Any, Any]]:
        """``SafeLoader.construct_yaml_map``, noting the keys written more than once (a merge's keys aside)."""
        data: dict[Any, Any] = {}
        yield data
        lines: dict[Any, list[int]] = {}
        for key_node, _ in node.value:  # before construct_mapping, which merges ``<<`` into the node's keys
            if isinstance(key_node, yaml.ScalarNode) and key_node.tag != MERGE_TAG:
                lines.setdefault(self.construct_object(key_node), []).append(key_node.start_mark.line + 1)
        data.update(self.construct_mapping(node))
        self.repeated += [Repeated(data, key, len(at), tuple(at)) for key, at in lines.items() if len(at) > 1]


_Loader.add_constructor("tag:yaml.org,2002:map", _Loader.construct_checked_map)


def parse_text(text: str, kind: Kind) -> tuple[Any, list[Repeated]]:
    """The file's data and the keys it repeats; the parser's own errors (``json.JSONDecodeError``,
    ``yaml.YAMLError``, RecursionError, ValueError) as it raises them."""
    if kind == "JSON":
        repeated: list[Repeated] = []

        def mapping(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
            data = dict(pairs)
            if len(data) < len(pairs):
                counts = Counter(key for key, _ in pairs)
                repeated.extend(Repeated(data, key, n) for key, n in counts.items() if n > 1)
            return data

        return json.loads(text, object_pairs_hook=mapping), repeated
    loader = _Loader(text)
    try:
        return loader.get_single_data(), loader.repeated
    finally:
        loader.dispose()


def locate(data: Any, repeated: list[Repeated]) -> list[tuple[Location, Repeated]]:
    """Each repeated key with where its mapping is in ``data``, in the file's order (a mapping that aliases reach
    by several ways at the first; one not found at the top)."""
    wanted: dict[int, list[Repeated]] = {}
    for r in repeated:
        wanted.setdefault(id(r.mapping), []).append(r)
    found: list[tuple[Location, Repeated]] = []
    seen: set[int] = set()
    stack: list[tuple[Location, Any]] = [((), data)]
    while stack and wanted:
        loc, node = stack.pop()
        if not isinstance(node, dict | list) or id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, dict):
            found += [(loc, r) for r in wanted.pop(id(node), [])]
            children = [((*loc, k), v) for k, v in node.items() if isinstance(k, str)]
        else:
            children = [((*loc, i), v) for i, v in enumerate(node)]
        stack += reversed(children)
    return found + [((), r) for left in wanted.values() for r in left]
