"""The arm's force: a Kinova Gen3 rated for 4 kg (``max_payload``) exerts about 39 N in any direction, but the
payload rule weighed only what the arm bears up, so pressing a 1:1 lever's near end down with about 80 N raised an
8 kg anvil on its far end in 5 of 6 worlds. A push, a drag or a press on what the arm does not hold up now takes its
share of the rating too, once it moves something up or sideways; a press that moves nothing but down does not."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.robots.arm.arm_payload import PAYLOAD_CONDITION
from robotool.rollout import Rollout
from robotool.task.task_model import Task
from robotool.verify import world_failure

LEVER = FIXTURES / "layouts" / "arm_heavy_anvil_on_a_lever.yaml"
PRESS = (FIXTURES / "cheats" / "arm_press_a_lever_under_a_heavy_anvil.py").read_text()


def _press(run_texts: Any, task: Task) -> list[Rollout]:
    return list(run_texts(task, [PRESS] * 3, seed=11))


def test_pressing_a_lever_down_under_a_heavy_anvil_is_over_the_payload(run_texts: Any) -> None:
    for rollout in _press(run_texts, tasks.load(LEVER)):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        failure = world_failure(rollout) or ""
        assert re.search(
            r"cannot press beam: \d+ N on it with anvil touching it, over the 39 N the arm.s 4\.0 kg", failure
        )
        press = rollout.calls[-1]
        assert press.outcome == "refused" and press.measured["force"] > 39.2 and press.measured["mass"] == 0.0, press


def test_the_same_lever_raises_a_light_anvil(run_texts: Any, tmp_path: Path) -> None:
    """The control: a 2 kg anvil on the same lever, and a 5 kg block on the table out of the way (the scene's movable
    objects could weigh more than the payload: the arm's load is weighed)."""
    text = LEVER.read_text()
    block = "  - {name: block, shape: box, center: [0.25, 0.30, 0.03], size: [0.06, 0.06, 0.06], mass: 5.0}\n"
    assert "mass: 8.0" in text
    path = tmp_path / "lever.yaml"
    path.write_text(text.replace("mass: 8.0", "mass: 2.0").replace("goal:\n", block + "goal:\n"))
    for rollout in _press(run_texts, tasks.load(path)):
        assert rollout.success, world_failure(rollout)
        assert rollout.conditions.get(PAYLOAD_CONDITION) is True, rollout.conditions
