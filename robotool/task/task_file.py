"""Reading a task file (YAML or JSON, format 1) and checking it: :func:`load_task`, :func:`parse_task`.

:func:`load_task` reports *every* problem with its field path in a :class:`TaskFileError`, never a raw
traceback: the model's own checks, then checks that need the whole scene (names, goal, limits, geometry).
"""

from __future__ import annotations

import difflib
import json
import reprlib
import stat
import sys
import types
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydantic import BaseModel, ValidationError

from robotool import robots
from robotool.task import geometry, task_text
from robotool.task.limit_rules import limit_problems
from robotool.task.scene import reserved_name
from robotool.task.task_model import MAX_OBJECTS, WHY_MAX_OBJECTS, Task
from robotool.task.task_problem import Problem

RESTING_TOLERANCE = 0.01  # m: how far an object may float above or sink into its support
OVERLAP_TOLERANCE = 0.001  # m: solid objects may touch, not interpenetrate
RESTING_SLOPE = 45.0  # degrees: an overlap whose way out is at most this far from vertical is a resting one
GRASP_POINT_TOLERANCE = 0.005  # m: how far outside its object a graspable point may lie
KEY_SYNONYMS = {  # words people write for a key, and the key the format uses
    "rotation": "rpy", "orientation": "rpy", "euler": "rpy", "position": "center", "pos": "center",
    "centre": "center", "dimensions": "size", "extent": "size", "weight": "mass", "type": "shape",
    "grasp_point": "graspable_point", "grasp": "graspable_point", "handle": "graspable_point", "fixed": "movable",
    "description": "notes", "note": "notes", "objects_list": "objects", "task": "name", "version": "format",
}  # fmt: skip


class TaskFileError(ValueError):
    """A task file that cannot be used; ``problems`` lists every problem found (one line when there is one)."""

    def __init__(self, source: str, problems: list[Problem]):
        self.source = source
        self.problems = problems
        if len(problems) == 1:  # one mistake, one line
            super().__init__(f"{source}: {problems[0]}")
            return
        lines = "\n".join(f"  - {p}" for p in problems)
        super().__init__(f"{source}: {len(problems)} problems\n{lines}")


def _plain(text: str) -> bool:
    """Whether a name or key is shown in a field path as it is written (printable, short); any other, such as one
    with a line break or a control character in it, is shown as its bounded repr, so the path stays one line."""
    return text.isprintable() and 0 < len(text) <= 64


def _format_loc(loc: tuple[int | str, ...], raw: Any) -> str:
    """Turn a pydantic error location into ``objects[2](hammer).size[0]``."""
    out = ""
    node = raw
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
            node = node[part] if isinstance(node, list) and part < len(node) else None
            name = node.get("name") if isinstance(node, Mapping) else None
            if isinstance(name, str):
                out += f"({name})" if _plain(name) else f"({shown(name)})"
        else:
            key = part if _plain(part) else f"[{shown(part)}]"
            out += f".{key}" if out and not key.startswith("[") else key
            node = node.get(part) if isinstance(node, Mapping) else None
    return out


class _Shown(reprlib.Repr):
    def repr_int(self, x: int, level: int) -> str:
        try:
            return super().repr_int(x, level)
        except ValueError:  # more digits than Python converts (YAML reads 0x... of any length)
            return f"an integer of about {int(x.bit_length() * DIGITS_PER_BIT)} digits"


DIGITS_PER_BIT = 0.30103  # log10(2)
_SHOWN = _Shown()
_SHOWN.maxlevel, _SHOWN.maxstring, _SHOWN.maxother = 2, 80, 80
_SHOWN.maxlist = _SHOWN.maxtuple = _SHOWN.maxdict = _SHOWN.maxset = 6


def shown(value: Any) -> str:
    """A value from a task file as an error message shows it: its repr, cut short however large or deep the value
    is (a file's aliases can make a small file hold a value whose whole repr would not fit in memory)."""
    return _SHOWN.repr(value)


def _friendly(error: Mapping[str, Any]) -> str:
    kind, msg = error["type"], error["msg"]
    value = error.get("input")
    if kind == "extra_forbidden":
        return "unknown key"
    if kind == "literal_error":
        return f"{msg} (got {shown(value)})"
    if kind == "string_pattern_mismatch":
        return f"names use only lowercase letters, digits and '_' (got {shown(value)})"
    if kind == "missing":
        return "required field is missing"
    if msg.startswith("Value error, "):
        return msg.removeprefix("Value error, ")
    if value is not None and not isinstance(value, Mapping | list):
        return f"{msg} (got {shown(value)})"
    return msg


def _model_problems(error: ValidationError, raw: Any, model: type[BaseModel] | None = None) -> list[Problem]:
    problems = []
    for e in error.errors():
        loc = tuple(p for p in e["loc"] if not (isinstance(p, str) and p.startswith("function-")))
        # Tagged tuples report a position per element; literal unions add the type name.
        loc = tuple(p for p in loc if p not in ("tuple[float, float]",))
        message = _friendly(e)
        if e["type"] == "extra_forbidden" and loc and isinstance(loc[-1], str):
            message = _unknown_key(loc[-1], _keys_at(model or Task, loc[:-1]))
        if e["type"] == "invalid_key":  # its location ends with the key itself, as a list index or a text
            loc, message = loc[:-1], f"{_key_text(e['input'])}: keys must be strings"
        problems.append(Problem(path=_format_loc(loc, raw), message=message))
    return problems


def _key_text(key: Any) -> str:
    """A key as a message names it: ``key 1 (a number)``, ``key null``."""
    if key is None:
        return "key null (an empty key)"
    if isinstance(key, bool):
        return f"key {str(key).lower()} (a boolean)"
    kind = "a number" if isinstance(key, int | float) else f"a {type(key).__name__}"
    return f"key {shown(key)} ({kind})"


def _keys_at(model: type[BaseModel], loc: tuple[int | str, ...]) -> list[str]:
    """The keys the model nested at ``loc`` accepts (``objects[0].fragile`` -> Fragile's keys)."""
    current: type[BaseModel] | None = model
    for part in loc:
        if current is None:
            return []
        if isinstance(part, int):
            continue
        field = current.model_fields.get(part)
        current = _nested_model(field.annotation) if field is not None else None
    return list(current.model_fields) if current is not None else []


def _nested_model(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model inside an annotation such as ``list[SceneObject]`` or ``Fragile | None``."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    if typing.get_origin(annotation) in (list, typing.Union, types.UnionType):
        return next((m for a in typing.get_args(annotation) if (m := _nested_model(a)) is not None), None)
    return None


def _unknown_key(key: str, keys: list[str]) -> str:
    """``unknown key 'rotation' (did you mean 'rpy'?); keys here: ...``."""
    guess = KEY_SYNONYMS.get(key.lower())
    if guess not in keys:
        close = difflib.get_close_matches(key.lower(), keys, n=1, cutoff=0.6)
        guess = close[0] if close else None
    hint = f" (did you mean {guess!r}?)" if guess else ""
    listing = f"; keys here: {', '.join(keys)}" if keys else ""
    return f"unknown key {shown(key)}{hint}{listing}"


def _object_path(task: Task, index: int) -> str:
    return f"objects[{index}]({task.objects[index].name})"


def _check_semantics(task: Task) -> list[Problem]:
    """Checks that need the whole scene: names, goal, limits, geometry."""
    problems: list[Problem] = []
    seen: dict[str, int] = {}
    for i, obj in enumerate(task.objects):
        if obj.name in seen:
            problems.append(
                Problem(
                    path=f"objects[{i}].name", message=f"duplicate name {obj.name!r} (also objects[{seen[obj.name]}])"
                )
            )
        seen.setdefault(obj.name, i)
        reserved = reserved_name(obj.name)
        if reserved is not None:
            problems.append(Problem(path=f"objects[{i}].name", message=reserved))

    robot = task.robot
    try:
        limits = limit_problems(robot.limits, task.limits)
    except ValidationError as e:
        model = robots.get(robot.type).limits
        limits = [
            Problem(path=f"robot.limits.{p.path}" if p.path else "robot.limits", message=p.message)
            for p in _model_problems(e, robot.limits, model)
        ]
    limits_ok = not limits
    problems += limits
    robot_type = robots.get(robot.type)
    problems += robot_type.rules.check_robot(task)

    kind = task.goal.kind
    target = task.goal.object
    if kind not in robot_type.goals:
        allowed = ", ".join(sorted(robot_type.goals))
        message = f"{robot_type.article} {robot.type} cannot have a '{kind}' goal (use one of: {allowed})"
        problems.append(Problem(path=f"goal.{kind}", message=message))
    elif target not in seen:
        problems.append(
            Problem(path=f"goal.{kind}", message=f"no object named {target!r} (objects: {', '.join(seen)})")
        )
    else:
        obj = task.objects[seen[target]]
        if kind == "pressed" and obj.shape != "button":
            problems.append(Problem(path="goal.pressed", message=f"{target!r} is a {obj.shape}, not a button"))
        if kind in ("grasped", "lifted", "lowered") and not obj.movable:
            problems.append(Problem(path=f"goal.{kind}", message=f"{target!r} is fixed and cannot be moved"))
        if kind == "robot_on" and obj.shape == "cloth":
            problems.append(Problem(path="goal.robot_on", message=f"{target!r} is a cloth and cannot carry the robot"))

    if limits_ok and len(seen) == len(task.objects):  # geometry needs unique names and limits
        problems += _check_geometry(task)
    return problems


def _xy_bounds(parts: list[geometry.Part]) -> np.ndarray:
    """An object's x-y bounds ``[xmin, ymin, xmax, ymax]``, from its parts' world bounds."""
    bounds = [p.aabb() for p in parts]
    lo, hi = np.min([b[0] for b in bounds], axis=0), np.max([b[1] for b in bounds], axis=0)
    return np.array([lo[0], lo[1], hi[0], hi[1]])


def _check_geometry(task: Task) -> list[Problem]:
    parts = {o.name: geometry.object_parts(o) for o in task.objects}
    names = list(parts)
    margin = np.array([-1, -1, 1, 1]) * RESTING_TOLERANCE
    xy = np.array([_xy_bounds(parts[n]) for n in names]).reshape(-1, 4) + margin
    problems: list[Problem] = []
    sunk: set[frozenset[str]] = set()  # pairs already reported as one sunk into the other
    for i, obj in enumerate(task.objects):
        if obj.graspable_point is not None:
            off = geometry.distance_to_parts(parts[obj.name], obj.graspable_point)
            if off > GRASP_POINT_TOLERANCE:
                problems.append(
                    Problem(
                        path=f"{_object_path(task, i)}.graspable_point",
                        message=f"{list(obj.graspable_point)} lies {off:.3f} m outside {obj.name!r}; a graspable point "
                        "is in world coordinates (metres) and must lie within or on its object",
                    )
                )
        # only what lies under its x-y bounds can carry it or be sunk into: one test for all, not one per pair
        under = (xy[:, 0] <= xy[i, 2]) & (xy[:, 2] >= xy[i, 0]) & (xy[:, 1] <= xy[i, 3]) & (xy[:, 3] >= xy[i, 1])
        others = {names[k]: parts[names[k]] for k in np.flatnonzero(under) if k != i}
        contact = geometry.resting_contact(parts[obj.name], others, obj.center[2], RESTING_TOLERANCE)
        if contact.penetration > RESTING_TOLERANCE:
            sunk.add(frozenset((obj.name, contact.into)))
            problems.append(
                Problem(
                    path=f"{_object_path(task, i)}.center",
                    message=f"sunk {contact.penetration:.3f} m into {contact.into}",
                )
            )
        elif contact.gap > RESTING_TOLERANCE:
            problems.append(
                Problem(
                    path=f"{_object_path(task, i)}.center",
                    message=f"floats {contact.gap:.3f} m above the surface below it",
                )
            )
    problems += _overlap_problems(task, parts, sunk)
    problems += _sheet_problems(task)
    problems += robots.get(task.robot.type).rules.check_start(task)
    return problems


def _overlap_problems(task: Task, parts: dict[str, list[geometry.Part]], sunk: set[frozenset[str]]) -> list[Problem]:
    """Solid objects may touch but not interpenetrate at the start, whichever of them is movable: the simulator
    would push them apart in the first step (a weight placed 1.5 cm inside a button's face pressed it with no
    program). Two exceptions: a movable object resting on another (it is the higher of the two, and the overlap's way
    out is at most :data:`RESTING_SLOPE` from vertical) may sink into it by the resting check's
    :data:`RESTING_TOLERANCE`, and a sheet (:attr:`~robotool.task.scene.SceneObject.is_sheet`) lies through what is
    on it (the simulator lets it pass through every object but the ground and the robot)."""
    problems = []
    solid = [i for i, o in enumerate(task.objects) if not o.is_sheet]
    vertical = np.cos(np.radians(RESTING_SLOPE))
    for i, j in _near_pairs(task, parts, solid):
        a, b = task.objects[i], task.objects[j]
        if frozenset((a.name, b.name)) in sunk:
            continue
        depth, direction = geometry.solids_penetration(parts[a.name], parts[b.name])
        higher = a if a.center[2] > b.center[2] else b if b.center[2] > a.center[2] else None
        resting = higher is not None and higher.movable and abs(direction[2]) >= vertical
        if depth <= (RESTING_TOLERANCE if resting else OVERLAP_TOLERANCE):
            continue
        at = i if a.movable and not b.movable else j  # the one to move: a movable one beside a fixed one
        problems.append(
            Problem(
                path=f"{_object_path(task, at)}.center",
                message=f"{a.name!r} and {b.name!r} overlap by {depth:.3f} m: objects may touch but not "
                "interpenetrate (the simulator would push them apart at the start); move one of them apart",
            )
        )
    return problems


def _near_pairs(task: Task, parts: dict[str, list[geometry.Part]], indices: list[int]) -> list[tuple[int, int]]:
    """The pairs (i < j) of ``indices`` whose spheres around their parts' corners meet: only those can overlap (the
    exact test is about 0.1 ms a pair; a file of 250 objects took 3 s over every pair, quadratic in what it lists)."""
    corners = [np.vstack([p.corners() for p in parts[task.objects[i].name]]) for i in indices]
    centre = np.array([c.mean(axis=0) for c in corners]).reshape(-1, 3)
    radius = np.array([np.linalg.norm(c - m, axis=1).max() for c, m in zip(corners, centre, strict=True)])
    apart = np.linalg.norm(centre[:, None] - centre[None, :], axis=2) > radius[:, None] + radius[None, :]
    near = np.argwhere(np.triu(~apart, k=1))
    return [(indices[a], indices[b]) for a, b in near.tolist()]


def _sheet_problems(task: Task) -> list[Problem]:
    """A sheet (paper, card: :attr:`~robotool.task.scene.SceneObject.is_sheet`) lies flat on the ground, where the
    simulator lets it rest (it passes through other objects: what lies on it rests on it by rule), and is never
    magnetic (a magnet's hold would make it a rigid plate: held by one end, it would carry or push what it is stuck
    to). Found by an adversarial run: a fixed 0.2 mm sheet of 10 g tilted from the floor up to a 0.34 m sofa's edge
    passed the ground rule by its low end, and a legged robot walked up it as up a rigid ramp, 0.22 m over its step
    limit."""
    problems = []
    for i, obj in enumerate(task.objects):
        if not obj.is_sheet:
            continue
        advice = "make it thicker or heavier than a sheet (a plate) to"
        rise = obj.top - obj.bottom - min(obj.size)
        if obj.bottom > RESTING_TOLERANCE:
            problems.append(
                Problem(
                    path=f"{_object_path(task, i)}.center",
                    message=f"a sheet lies on the ground, not {obj.bottom:.3f} m above it (it would pass through what "
                    f"is under it); {advice} lay it on another object",
                )
            )
        elif rise > RESTING_TOLERANCE:
            problems.append(
                Problem(
                    path=f"{_object_path(task, i)}.rpy",
                    message=f"a sheet lies flat on the ground, not tilted (its far end {rise:.3f} m above its near "
                    f"end: a sheet is too limp to hold itself up as a ramp); {advice} lean it on something",
                )
            )
        if obj.magnetic:
            problems.append(
                Problem(
                    path=f"{_object_path(task, i)}.magnetic",
                    message=f"a sheet is limp and cannot be magnetic (a magnet's hold would make it rigid); {advice} "
                    "make it magnetic",
                )
            )
    return problems


def parse_task(data: Any, source: str = "<task>") -> Task:
    """Validate already-loaded task data (a mapping), raising :class:`TaskFileError`."""
    if not isinstance(data, Mapping):
        raise TaskFileError(source, [Problem(path="", message="a task file must be a mapping of keys")])
    objects = data.get("objects")
    if isinstance(objects, list) and len(objects) > MAX_OBJECTS:
        message = f"{len(objects)} objects; a task holds at most {MAX_OBJECTS} ({WHY_MAX_OBJECTS})"
        raise TaskFileError(source, [Problem(path="objects", message=message)])
    unknown_robot = _unknown_robot_type(data)
    try:
        task = Task.model_validate(data)
    except ValidationError as e:
        raise TaskFileError(source, _with_robot_problem(_model_problems(e, data), unknown_robot)) from None
    except RecursionError:
        raise TaskFileError(source, [Problem(path="", message=NESTED_TOO_DEEP)]) from None
    if unknown_robot is not None:
        raise TaskFileError(source, [unknown_robot])
    problems = _check_semantics(task)
    if problems:
        raise TaskFileError(source, problems)
    return task


def _unknown_robot_type(data: Mapping[str, Any]) -> Problem | None:
    """``robot.type`` that names no registered robot (the registered ones listed, the closest suggested)."""
    robot = data.get("robot")
    kind = robot.get("type") if isinstance(robot, Mapping) else None
    if isinstance(kind, str) and kind not in robots.names():
        return Problem(path="robot.type", message=robots.registry.unknown_message(kind))
    return None


def _with_robot_problem(problems: list[Problem], robot: Problem | None) -> list[Problem]:
    """The model's problems with the robot type's in the place of its key (after format, name, category and
    instruction, before objects and goal)."""
    if robot is None:
        return problems
    after = ("objects", "goal")
    at = next((i for i, p in enumerate(problems) if p.path.startswith(after)), len(problems))
    return [*problems[:at], robot, *problems[at:]]


class NotARegularFile(OSError):
    """A path that names a directory, a named pipe, a socket or a device, not a file to read."""


def read_at_most(path: Path, limit: int) -> bytes:
    """The bytes of the regular file at ``path``, but never more than ``limit + 1`` of them: a caller that gets more
    than ``limit`` refuses the file without having read it whole (a file of gigabytes). What is not a regular file is
    refused before it is opened (:class:`NotARegularFile`): a named pipe would wait for a writer for ever, a device
    (``/dev/zero``) never ends. OSError as :meth:`~pathlib.Path.read_bytes` raises it."""
    mode = path.stat().st_mode
    if not stat.S_ISREG(mode):
        raise NotARegularFile(f"not a regular file ({SPECIAL_FILES.get(stat.S_IFMT(mode), 'a device')})")
    with path.open("rb") as f:
        return f.read(limit + 1)


def load_task(path: str | Path) -> Task:
    """Load and validate a YAML or JSON task file (of at most :data:`MAX_TASK_FILE_BYTES`)."""
    path = Path(path)
    source = str(path)
    try:
        data = read_at_most(path, MAX_TASK_FILE_BYTES)
        if len(data) > MAX_TASK_FILE_BYTES:
            raise TaskFileError(source, [Problem(path="", message=TOO_LARGE)])
        text = data.decode("utf-8")
    except FileNotFoundError:
        raise TaskFileError(source, [Problem(path="", message="file not found")]) from None
    except NotARegularFile as e:
        raise TaskFileError(source, [Problem(path="", message=f"{e}; give a task file")]) from None
    except (OSError, UnicodeDecodeError) as e:
        raise TaskFileError(source, [Problem(path="", message=f"cannot read the file: {e}")]) from None
    kind: task_text.Kind = "JSON" if path.suffix.lower() == ".json" else "YAML"
    try:
        data, repeated = task_text.parse_text(text, kind)
    except json.JSONDecodeError as e:
        raise TaskFileError(source, [_syntax_problem("JSON", text, e.lineno, e.colno, e.msg)]) from None
    except yaml.MarkedYAMLError as e:
        raise TaskFileError(source, [_yaml_problem(text, e)]) from None
    except yaml.YAMLError as e:
        raise TaskFileError(source, [_syntax_problem("YAML", text, None, None, " ".join(str(e).split()))]) from None
    except RecursionError:
        raise TaskFileError(source, [Problem(path="", message=NESTED_TOO_DEEP)]) from None
    except ValueError as e:  # a number of more digits than Python converts (the parsers raise nothing more precise)
        raise TaskFileError(source, [_syntax_problem(kind, text, None, None, _too_many_digits(e))]) from None
    if repeated:
        raise TaskFileError(source, [_repeated_problem(loc, r, data) for loc, r in task_text.locate(data, repeated)])
    return parse_task(data, source)


SPECIAL_FILES = {stat.S_IFDIR: "a directory", stat.S_IFIFO: "a named pipe", stat.S_IFSOCK: "a socket"}


def _repeated_problem(loc: task_text.Location, repeated: task_text.Repeated, data: Any) -> Problem:
    """``objects[0](milk): key 'mass' given twice (lines 12 and 13); give each key once``."""
    times = "twice" if repeated.count == 2 else f"{repeated.count} times"
    lines = [str(n) for n in repeated.lines]
    where = f" (lines {', '.join(lines[:-1])} and {lines[-1]})" if lines else ""
    message = f"key {shown(repeated.key)} given {times}{where}; give each key once"
    return Problem(path=_format_loc(loc, data), message=message)


def _too_many_digits(error: ValueError) -> str:
    """The parser's error for a number with thousands of digits, without Python's advice to raise the limit."""
    if "digits" in str(error):
        return f"a number has more than {sys.get_int_max_str_digits()} digits"
    return " ".join(str(error).split())


MAX_TASK_FILE_BYTES = 1_000_000
"""A task file's largest size: a task of the most objects allowed (:data:`MAX_OBJECTS`), each with long notes, is a
tenth of it; the built-in ones are 1-3 kB."""
TOO_LARGE = f"the file is larger than {MAX_TASK_FILE_BYTES // 1000} kB (a task file is a few kB)"
NESTED_TOO_DEEP = "lists or mappings are nested too deeply to read (a task file nests a few levels)"


def _yaml_problem(text: str, error: yaml.MarkedYAMLError) -> Problem:
    """Where YAML broke (line, column, the line's text) and, when it says so, where the broken part began."""
    mark = error.problem_mark or error.context_mark
    line, column = (mark.line + 1, mark.column + 1) if mark is not None else (None, None)
    problem = _syntax_problem("YAML", text, line, column, error.problem or error.context or "cannot be read")
    start = error.context_mark
    if error.problem_mark is not None and error.context and start is not None and start.line != mark.line:
        began = text.splitlines()[start.line].strip() if start.line < len(text.splitlines()) else ""
        problem.message += f" ({error.context} that began at line {start.line + 1}: `{began}`)"
    return problem


def _syntax_problem(kind: str, text: str, line: int | None, column: int | None, what: str) -> Problem:
    """``not valid YAML at line 3, column 12: <what>: `the offending line```."""
    if line is None:
        return Problem(path="", message=f"not valid {kind}: {what}")
    lines = text.splitlines()
    shown = lines[line - 1].strip() if 0 < line <= len(lines) else ""
    where = f"line {line}" + (f", column {column}" if column else "")
    return Problem(path="", message=f"not valid {kind} at {where}: {what}" + (f": `{shown}`" if shown else ""))
