"""The LM-free search planner: generate-and-test over geometric skill macros, verified in simulation.

``solve(task)`` returns the same :class:`~robotool.solution.Solution` as the RoboTool program, with
typed stage outputs, without any language model. Modules: :mod:`~robotool.planner.codegen` (program
text, plan steps, parameters), :mod:`~robotool.robots.quadruped.predict` (boxes, surfaces, walk prediction),
:mod:`~robotool.robots.arm.macros` and :mod:`~robotool.robots.quadruped.macros` (the macros and the
candidate programs they make), :mod:`~robotool.planner.search` (ordering and batched verification),
:mod:`~robotool.planner.solve` (the whole pipeline).
"""

from robotool.planner.solve import solve

__all__ = ["solve"]
