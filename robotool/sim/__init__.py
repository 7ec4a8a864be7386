"""Physics: task -> MuJoCo model, batched backends, skill controllers and the lockstep runner.

Modules, one job each:

- :mod:`robotool.sim.embodiment` — **the embodiment-controller interface** that every robot implements
  (model building, skill start/tick/query over batched state, found through the robot registry by
  ``task.robot.type``), and goal trackers; each robot's controller lives in its package,
  ``robotool/robots/<name>/<name>_controller.py``.
- :mod:`robotool.sim.build` — ``build(task) -> Scene`` (the ``MjModel`` made through ``MjSpec``, the robot added
  by ``embodiment_for(task)``); :mod:`robotool.sim.compiled_scene` — ``Scene``, the model and its id tables.
- :mod:`robotool.sim.backend` — the ``BatchedSim`` protocol, ``BatchState``, perturbations;
  :mod:`robotool.sim.backend_choice` — ``make_sim``; backends in :mod:`~robotool.sim.backend_mujoco` (C, threads)
  and :mod:`~robotool.sim.backend_warp`.
- :mod:`robotool.sim.magnets` — magnetic objects weld on contact.
- :mod:`robotool.sim.goals` — goal sub-conditions; :mod:`robotool.sim.object_goals` — lifted and lowered objects.
- :mod:`robotool.sim.cloth` — cloth as hinged links.
- :mod:`robotool.sim.lockstep` — ``run_sessions``: N program sessions in N worlds, one ``Rollout`` each.
"""

from robotool.sim.backend import BatchedSim, BatchState, Perturbation, default_backend
from robotool.sim.backend_choice import make_sim
from robotool.sim.build import build, embodiment_for
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import Embodiment, GoalTracker, QueryError, SkillController, SkillEnd
from robotool.sim.goals import goal_tracker
from robotool.sim.lockstep import run_programs, run_sessions, trusted_sessions
from robotool.vocabulary import BackendName

__all__ = [
    "BackendName",
    "BatchState",
    "BatchedSim",
    "Embodiment",
    "GoalTracker",
    "Perturbation",
    "QueryError",
    "Scene",
    "SkillController",
    "SkillEnd",
    "build",
    "default_backend",
    "embodiment_for",
    "goal_tracker",
    "make_sim",
    "run_programs",
    "run_sessions",
    "trusted_sessions",
]
