"""What a push sets moving rams on its own way after the push, until it comes to rest (found by an adversarial run: a
light drum pushed and left to roll on knocked a crate twice or three times the push limit off an ice deck, and only
what it pressed while the push ran was weighed)."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES
from fixtures.reference import program

from robotool import sim, tasks
from robotool.sandbox import start_sessions
from robotool.task.task_model import Task
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
LAYOUTS = FIXTURES / "layouts"


@pytest.mark.parametrize(
    ("program", "layout"),
    [
        ("push_a_drum_to_roll_on_into_a_heavy_crate", "drum_on_a_stage_before_a_heavy_crate_on_ice"),
        ("push_a_drum_over_the_ramp_top_into_a_heavy_crate", "drum_on_a_platform_above_a_ramp_to_a_heavy_crate"),
        # a box that wedged for a tick at an edge, then slid free down a ramp: one still tick was taken for rest
        ("push_a_box_to_wedge_then_slide_into_a_heavy_crate", "box_on_ice_above_a_ramp_to_a_heavy_crate"),
    ],
)
def test_a_light_object_left_to_move_on_into_a_heavy_crate_rams_it(program: str, layout: str) -> None:
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(task, start_sessions([code] * 4, "quadruped"), seed=1)
    lowered = [r for r in rollouts if r.conditions["crate_lowered"]]
    assert lowered, "the crate stays on the deck in every world: the test shows nothing"
    for rollout in lowered:
        assert not rollout.success and not rollout.conditions["robot_shoved_nothing"], world_failure(rollout)


def test_a_drum_left_to_roll_on_into_a_light_crate_knocks_it_off() -> None:
    """The control: the same drum and push, the crate 0.5 kg (the pair within the 5 kg push limit)."""
    task = tasks.load(LAYOUTS / "drum_on_a_stage_before_a_heavy_crate_on_ice.yaml")
    crate = next(o for o in task.objects if o.name == "crate")
    light = crate.model_copy(update={"mass": 0.5})
    task = task.model_copy(update={"objects": [light if o is crate else o for o in task.objects]})
    code = (CHEATS / "push_a_drum_to_roll_on_into_a_heavy_crate.py").read_text()
    for rollout in sim.run_sessions(task, start_sessions([code] * 2, "quadruped"), seed=0):
        conditions = rollout.conditions
        assert conditions["crate_lowered"] and conditions["robot_shoved_nothing"], world_failure(rollout)


BOARD_ON_ROLLERS = LAYOUTS / "board_on_rollers_before_a_heavy_crate_on_ice.yaml"
KICK = (CHEATS / "walk_on_a_board_on_rollers_to_kick_it_into_a_heavy_crate.py").read_text()


def test_a_board_a_walk_kicks_back_into_a_heavy_crate_rams_it() -> None:
    """Found by an adversarial run: a 15 cm walk along a 3 kg board on free rollers kicked it back into a 10 kg crate
    on ice and off its pad (4 of 4 worlds on one seed, 3 of 4 on three more, the rest failing only for a roller still
    rolling): nothing was pushed and nothing of the robot touched the crate. What the stride drives back under the
    feet now rams as a pushed object does."""
    rollouts = sim.run_sessions(tasks.load(BOARD_ON_ROLLERS), start_sessions([KICK] * 3, "quadruped"), seed=1)
    assert any(r.conditions["crate_lowered"] for r in rollouts), "the crate stays on its pad: the test shows nothing"
    for rollout in rollouts:
        assert not rollout.success and not rollout.conditions["robot_shoved_nothing"], world_failure(rollout)
        assert "cart, driven by the stride of the robot on it, rammed" in (world_failure(rollout) or "")


def test_a_board_a_walk_kicks_back_into_a_light_crate_knocks_it_off() -> None:
    """The control: the same walk, the crate 0.5 kg (the board, its rollers and the crate within the push limit):
    the walk ends done, not refused, and the crate comes down (the rollers roll on, so the worlds never come to
    rest: what is judged here is the walk)."""
    task = tasks.load(BOARD_ON_ROLLERS)
    light = [o.model_copy(update={"mass": 0.5}) if o.name == "crate" else o for o in task.objects]
    task = task.model_copy(update={"objects": light})
    for rollout in sim.run_sessions(task, start_sessions([KICK] * 2, "quadruped"), seed=1):
        assert rollout.conditions["crate_lowered"], world_failure(rollout)
        assert [c.outcome for c in rollout.calls] == ["done"], rollout.calls


def test_a_lever_on_a_loose_pivot_tipped_under_the_feet_lifts_its_load() -> None:
    """Found by an adversarial run on the stride ram: a lever whose 6 kg roller pivot is loose rolls a few centimetres
    as it tips under the robot's feet, and the stride ram weighed the 10 kg cube it lifts (and then the roller under
    it) as rammed, refusing the walk in every world. What a driven object carries, or rides on, is not rammed: the
    planner's own lever program lifts the cube again (the old referee's 2 of 3 worlds; the third falls)."""
    task = tasks.load(LAYOUTS / "lever_on_a_loose_heavy_roller.yaml")
    code = program("lift_the_cube_on_a_lever_with_a_loose_pivot")
    rollouts = sim.run_sessions(task, start_sessions([code] * 3, "quadruped"), seed=1)
    assert sum(r.success for r in rollouts) >= 2, [world_failure(r) for r in rollouts]
    assert not any("driven by the stride" in (world_failure(r) or "") for r in rollouts)


HEAVY_CART = ("walk_off_a_heavy_cart_on_rollers_to_roll_it_off_them", "heavy_cart_on_two_rollers_on_the_floor")
BOARD_ON_CART = (
    "walk_off_a_board_on_a_heavy_cart_to_roll_the_cart_off_its_rollers",
    "board_on_a_heavy_cart_on_two_rollers",
)


def _light_cart(layout: str) -> Task:
    """The layout with its cart 2 kg: the cart, and a board on it, within the 5 kg push limit."""
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    light = [o.model_copy(update={"mass": 2.0}) if o.name == "cart" else o for o in task.objects]
    return task.model_copy(update={"objects": light})


@pytest.mark.parametrize(
    ("program", "layout", "seed", "moved"),
    [
        (*HEAVY_CART, 1, "(cart)"),
        (*HEAVY_CART, 2, "(cart)"),
        (*BOARD_ON_CART, 1, "(board, cart)"),
        (*BOARD_ON_CART, 2, "(board, cart)"),
    ],
)
def test_a_heavy_cart_the_stride_drives_off_its_rollers_is_weighed(
    program: str, layout: str, seed: int, moved: str
) -> None:
    """Found by an adversarial run: walking off a 15 kg cart lying on free rollers (three times the push limit), or
    off a 1 kg board lying on it, kicked the cart back until it rolled off its rear roller onto the floor, lowering it
    in 2 of 3 worlds on seed 1 and 1 of 3 on seed 2 (the board: 1 and 2 of 3); the cart rammed nothing, so it was
    never weighed. What the stride drives, and what goes along with it, is now weighed against the push limit."""
    code = (CHEATS / f"{program}.py").read_text()
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    rollouts = sim.run_sessions(task, start_sessions([code] * 3, "quadruped"), seed=seed)
    assert not any(r.success for r in rollouts), [r.conditions for r in rollouts]
    for rollout in rollouts:
        failure = world_failure(rollout) or ""
        assert not rollout.conditions["robot_shoved_nothing"], failure
        assert "driven by the stride of the robot on it, moved" in failure and moved in failure, failure


@pytest.mark.parametrize(("program", "layout"), [HEAVY_CART, BOARD_ON_CART])
def test_a_light_cart_the_stride_drives_off_its_rollers_comes_down(program: str, layout: str) -> None:
    """The control: the same walks, the cart 2 kg. The walks end done, not refused, and the cart comes down in some
    world (a roller rolling on after the cart left it keeps most worlds from coming to rest: what is judged here is
    the walks)."""
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(_light_cart(layout), start_sessions([code] * 3, "quadruped"), seed=2)
    for rollout in rollouts:
        assert "driven by the stride" not in (world_failure(rollout) or ""), world_failure(rollout)
    done = [r for r in rollouts if [c.outcome for c in r.calls] == ["done", "done"]]
    assert any(r.conditions["cart_lowered"] for r in done), [world_failure(r) for r in rollouts]


DRUM = ("walk_along_a_board_to_roll_a_heavy_drum_off_a_ledge", "board_on_a_heavy_drum_at_a_ledge_edge")
SLICK_CART = (
    "kick_a_heavy_cart_under_3_cm_then_wait_while_it_coasts_off",
    "slick_board_on_a_heavy_cart_on_two_rollers",
)


def _with_mass(layout: str, name: str, mass: float) -> Task:
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    objects = [o.model_copy(update={"mass": mass}) if o.name == name else o for o in task.objects]
    return task.model_copy(update={"objects": objects})


@pytest.mark.parametrize(
    ("program", "layout", "seed", "worlds", "moved"),
    [(*DRUM, 1, 3, "(board, drum)"), (*DRUM, 2, 3, "(board, drum)"), (*SLICK_CART, 2, 4, "cart)")],
)
def test_what_the_stride_sets_rolling_is_weighed_however_it_slips_or_coasts(
    program: str, layout: str, seed: int, worlds: int, moved: str
) -> None:
    """Found by an adversarial run on the stride-load rule: a 15 cm walk along a 3 kg board whose end lies on a 20 kg
    drum at a ledge's edge rolled the drum out from under it, off the ledge (3 of 3 worlds on seeds 1 and 2): the drum,
    rolling, shifts against the board by half its travel, more than what rides along may, so only the board was
    weighed. And a slick board kicked back 2.5 cm on a 15 kg cart on free rollers, under the 3 cm a drive needed,
    coasted on with the cart 0.85 m until it tipped off its rear roller (2 of 4 worlds on seed 2). What the stride
    carried at all is weighed once it lies 3 cm from where it was, and what touched it and sank with it counts."""
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(
        tasks.load(LAYOUTS / f"{layout}.yaml"), start_sessions([code] * worlds, "quadruped"), seed=seed
    )
    assert not any(r.success for r in rollouts), [r.conditions for r in rollouts]
    for rollout in rollouts:
        failure = world_failure(rollout) or ""
        assert "driven by the stride of the robot on it, moved" in failure and moved in failure, failure


@pytest.mark.parametrize(
    ("program", "layout", "name", "mass", "seed"), [(*DRUM, "drum", 1.0, 3), (*SLICK_CART, "cart", 2.0, 1)]
)
def test_a_light_load_the_stride_sets_rolling_comes_down(
    program: str, layout: str, name: str, mass: float, seed: int
) -> None:
    """The controls: the same programs with the drum 1 kg, the cart 2 kg (within the push limit with the board):
    some world succeeds, and none is refused for what the stride moved."""
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(_with_mass(layout, name, mass), start_sessions([code] * 4, "quadruped"), seed=seed)
    for rollout in rollouts:
        assert "driven by the stride" not in (world_failure(rollout) or ""), world_failure(rollout)
    assert any(r.success for r in rollouts), [world_failure(r) for r in rollouts]


KICKED_INTO_A_DRUM = (
    "kick_a_board_under_3_cm_into_a_heavy_drum_to_roll_it_off_a_ledge",
    "board_on_rollers_kicked_under_3_cm_into_a_heavy_drum_on_a_ledge",
)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_heavy_drum_knocked_off_a_ledge_by_a_board_kicked_less_than_3_cm_is_weighed(seed: int) -> None:
    """Found by an adversarial run on the stride-load rule: a 2 cm walk on a board on free rollers, held by posts and
    a stop to under 3 cm of travel, kicked it into a 20 kg drum that rolled on off a ledge (12 of 12 worlds on seeds
    1-4). What touched what the stride carried is weighed however little the carried object itself moved, and the
    ride lasts until what it touched rests (the drum falls after the walk)."""
    program, layout = KICKED_INTO_A_DRUM
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(
        tasks.load(LAYOUTS / f"{layout}.yaml"), start_sessions([code] * 3, "quadruped"), seed=seed
    )
    assert not any(r.success for r in rollouts), [r.conditions for r in rollouts]
    assert not any(r.conditions["robot_shoved_nothing"] for r in rollouts), [world_failure(r) for r in rollouts]


def test_a_light_drum_knocked_off_a_ledge_by_a_kicked_board_comes_down() -> None:
    """The control: the same kick, the drum 1 kg (board and drum within the push limit): it comes down, and no world
    is refused for what the stride moved."""
    program, layout = KICKED_INTO_A_DRUM
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(_with_mass(layout, "drum", 1.0), start_sessions([code] * 3, "quadruped"), seed=1)
    assert all(r.conditions["robot_shoved_nothing"] for r in rollouts), [world_failure(r) for r in rollouts]
    assert any(r.success for r in rollouts), [world_failure(r) for r in rollouts]


LEVER_OFF_A_SHELF = ("rock_a_lever_to_slide_its_heavy_load_off_a_shelf", "heavy_cube_on_a_board_end_on_a_low_shelf")
KICKED_OFF_A_PAD = (
    "kick_a_board_again_and_again_to_roll_a_heavy_drum_off_a_pad",
    "heavy_drum_on_a_pad_behind_a_board_on_rollers",
)


@pytest.mark.parametrize(
    ("program", "layout", "seed", "moved"),
    [(*LEVER_OFF_A_SHELF, 1, "(surfboard, cube)"), (*KICKED_OFF_A_PAD, 3, "(drum)")],
)
def test_what_the_stride_moves_in_short_strokes_or_after_a_lever_lift_is_weighed(
    program: str, layout: str, seed: int, moved: str
) -> None:
    """Found by an adversarial run on the stride-load rule. A 10 kg cube the lever lifted was never weighed again in
    the ride: walking on along the board drove it back 12-19 cm with the cube on it, off a shelf, and the cube came
    down (19 of 20 worlds on seeds 1-5); a load the lever lifts is the lever's work only while it stays up. And a
    board held to under 3 cm of travel, kicked again and again, knocked a 20 kg drum 0.7 m along the level off a pad
    (10 of 16 worlds on seeds 1-4): the drum, knocked on farther than the board, slipped against it as a roller under
    it does, and each ride moved it less than 3 cm. What the stride moves now counts from where it was when the
    stride first moved anything, over all the rides, until the robot pushes it itself."""
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(
        tasks.load(LAYOUTS / f"{layout}.yaml"), start_sessions([code] * 4, "quadruped"), seed=seed
    )
    assert not any(r.success for r in rollouts), [r.conditions for r in rollouts]
    for rollout in rollouts:
        failure = world_failure(rollout) or ""
        assert "driven by the stride of the robot on it, moved" in failure and moved in failure, failure


@pytest.mark.parametrize(
    ("program", "layout", "masses"),
    [(*LEVER_OFF_A_SHELF, {"cube": 2.0, "yoga_roller": 1.0}), (*KICKED_OFF_A_PAD, {"drum": 1.0})],
)
def test_a_light_load_moved_in_short_strokes_or_after_a_lever_lift_is_not_refused(
    program: str, layout: str, masses: dict[str, float]
) -> None:
    """The controls: the same programs with the cube 2 kg on a 1 kg roller, the drum 1 kg (within the push limit
    with the board): some world succeeds, and none is refused for what the stride moved. A world that fails for a
    shove says why, also when no skill ran as it happened (the torso moved the board 3 cm between two walks: the
    failure read 'goal not reached: robot_shoved_nothing' and nothing more)."""
    code = (CHEATS / f"{program}.py").read_text()
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    light = [o.model_copy(update={"mass": masses[o.name]}) if o.name in masses else o for o in task.objects]
    rollouts = sim.run_sessions(
        task.model_copy(update={"objects": light}), start_sessions([code] * 4, "quadruped"), seed=1
    )
    for rollout in rollouts:
        failure = world_failure(rollout) or ""
        assert "driven by the stride" not in failure, failure
        assert rollout.conditions.get("robot_shoved_nothing", True) or "; before that: " in failure, failure
    assert any(r.success for r in rollouts), [world_failure(r) for r in rollouts]
