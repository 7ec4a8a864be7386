"""Robots: one package per embodiment (``robotool/robots/<name>/``) and the registry the rest of robotool asks.

Each package builds one :class:`RobotType` record, ``ROBOT``, that holds everything robot-specific (limits,
skills, goal kinds, task checks, description, key concepts, simulator embodiment, planner macros, error rules,
picture settings). :func:`get` finds a robot by the task file's ``robot.type``; plug-ins from other packages
register the same way (see :mod:`robotool.robots.registry`).
"""

from robotool.robots.registry import (
    ENTRY_POINT_GROUP,
    MODULES_VARIABLE,
    PictureSettings,
    RobotPluginError,
    RobotType,
    SearchMacros,
    UnknownRobotError,
    get,
    names,
    register,
    robots,
)

__all__ = [
    "ENTRY_POINT_GROUP",
    "MODULES_VARIABLE",
    "PictureSettings",
    "RobotPluginError",
    "RobotType",
    "SearchMacros",
    "UnknownRobotError",
    "get",
    "names",
    "register",
    "robots",
]
