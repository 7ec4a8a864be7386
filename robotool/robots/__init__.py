"""Robots: one package per embodiment (``robotool/robots/<name>/``) and the registry the rest of robotool asks.

Each package builds one :class:`RobotType` record, ``ROBOT``, that holds everything robot-specific (limits,
skills, goal kinds, and hooks grouped as task rules, description, simulator, planner, feedback and pictures).
:func:`get` finds a robot by the task file's ``robot.type``; plug-ins from other packages register the same way
(see :mod:`robotool.robots.registry`).
"""

from robotool.robots.registry import (
    ENTRY_POINT_GROUP,
    MODULES_VARIABLE,
    DescriptionHooks,
    FeedbackRules,
    PictureHooks,
    PictureSettings,
    RobotPluginError,
    RobotType,
    SearchMacros,
    SimHooks,
    TaskRules,
    UnknownRobotError,
    get,
    names,
    register,
    registered,
    robots,
)

__all__ = [
    "ENTRY_POINT_GROUP",
    "MODULES_VARIABLE",
    "DescriptionHooks",
    "FeedbackRules",
    "PictureHooks",
    "PictureSettings",
    "RobotPluginError",
    "RobotType",
    "SearchMacros",
    "SimHooks",
    "TaskRules",
    "UnknownRobotError",
    "get",
    "names",
    "register",
    "registered",
    "robots",
]
