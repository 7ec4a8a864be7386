"""The LM-free search planner: generate-and-test over geometric skill macros, verified in simulation.

``solve(task)`` returns the same :class:`~robotool.solution.Solution` as the RoboTool program, with
typed stage outputs, without any language model. Modules: :mod:`~robotool.planner.codegen` (program
text, plan steps, parameters), :mod:`~robotool.planner.layout` (boxes, surfaces, hypothetical placements),
:mod:`~robotool.planner.search` (ordering and batched verification),
:mod:`~robotool.planner.solve` (the whole pipeline). Each robot's macros, and the candidate programs they
make, are in its package (``RobotType.planner``, e.g. ``robotool/robots/<name>/<name>_macros.py``).
"""

from robotool.planner.solve import solve

__all__ = ["solve"]
