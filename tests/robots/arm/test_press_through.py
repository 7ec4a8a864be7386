"""What the arm presses down through a loose object onto a part that gives (a button's face) is weighed against its
payload (found by an adversarial run: a block resting on an upturned 50 N button, pressed by the closed fingers with
about 55 N, counted as a press into a support, which moves nothing but down)."""

from __future__ import annotations

from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.verify import world_failure


def _run(layout: str, program: str) -> list[Rollout]:
    task = tasks.load(FIXTURES / "layouts" / f"{layout}.yaml")
    return sim.run_sessions(task, start_sessions([(FIXTURES / program).read_text()] * 2, "arm"), seed=1)


def test_a_loose_block_pressed_onto_a_stiff_button_is_over_the_payload() -> None:
    cheat = "cheats/arm_press_a_loose_block_onto_a_stiff_button.py"
    for rollout in _run("arm_block_on_an_upturned_stiff_button", cheat):
        assert not rollout.success and not rollout.conditions["robot_carried_within_payload"], world_failure(rollout)
        assert "cannot press block" in (world_failure(rollout) or ""), world_failure(rollout)


def test_a_plate_pressed_onto_a_soft_button_within_the_payload_presses_it() -> None:
    rollouts = _run("arm_plate_on_an_upturned_soft_button", "programs/arm_press_a_plate_onto_a_soft_button.py")
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]
