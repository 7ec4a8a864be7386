"""The search's budget and what it learns between rounds: a round starts only when it is likely to end within the
budget of simulated world-seconds, and a program that starts as a failed one did, up to the call that failed, is
verified after those that do not.

The simulator is replaced by a scripted runner (a fixture: which program fails in which world seed, and how; each world
simulates a fixed time), so these tests check the search's bookkeeping, not the robot."""

from __future__ import annotations

import importlib

import pytest

from robotool import tasks
from robotool.planner import search as search_module
from robotool.planner.codegen import Point, Program
from robotool.planner.search import TICK_WEIGHT, Budget, Pace, Tried, failed_prefixes, repeats, search, work
from robotool.rollout import Rollout, SkillCall
from robotool.solution import Candidate, StageOutputs

PUSH = "push_to_position"
solve_module = importlib.import_module("robotool.planner.solve")  # the module, not the function it exports


class ScriptedRunner:
    """Fixture: runs no simulator; program ``code`` fails in the world seeds ``fails[code]`` (every program in every
    world: ``fails`` None), its first push ending with ``outcome`` there; each world simulates ``seconds``."""

    def __init__(self, fails: dict[str, set[int]] | None, seconds: float, outcome: str = "refused"):
        self.fails, self.seconds, self.outcome = fails, seconds, outcome
        self.batches: list[list[str]] = []

    def __call__(self, task, runs, *, backend=None):  # the shape of run_seeded
        self.batches.append([code for code, _ in runs])
        return [[self._rollout(code, r, s) for r, s in enumerate(seeds)] for code, seeds in runs]

    def _rollout(self, code: str, world: int, seed: int) -> Rollout:
        failed = self.fails is None or seed in self.fails.get(code, set())
        calls = [
            SkillCall(skill="get_position", args=["box"], outcome="done"),
            SkillCall(skill=PUSH, args=["box", [0.0, 0.0, 0.0]], outcome=self.outcome if failed else "done"),
        ]
        return Rollout(world=world, seed=seed, success=not failed, calls=calls, sim_time=self.seconds)


def _pushing(dx: float, then: float = 1.0) -> Program:
    """A program that pushes the box ``dx`` along x, then walks to x = ``then``."""
    prog = Program()
    ref = prog.query("get_position", "box", (0.0, 0.0, 0.0))
    prog.motion(PUSH, obj="box", point=Point.at(ref, (dx, 0.0, 0.0)), intent="push the box")
    prog.motion("walk_to_position", point=Point.at(None, (then, 0.0, 0.0)), intent="walk on")
    return prog


@pytest.fixture
def task():
    return tasks.load("sofa_traversing")


def _search(task, programs: list[Program], pace: Pace, rounds: int = 4) -> tuple[list[Tried], int]:
    budget = Budget(beam=1, rounds=rounds, work=pace.budget, verify=5)
    stages = lambda p: StageOutputs()  # noqa: E731
    return search(task, [programs], stages, worlds=3, seed=0, backend=None, budget=budget, pace=pace)


def test_a_batch_costs_its_worlds_simulated_seconds_and_its_longest_world_as_its_ticks() -> None:
    batch = [
        [Rollout(world=0, seed=0, success=True, sim_time=10.0)],
        [Rollout(world=0, seed=0, success=True, sim_time=4.0)],
    ]
    assert work(batch) == pytest.approx(14.0 + TICK_WEIGHT * 10.0)
    assert work([]) == 0.0


def test_a_round_starts_only_when_what_was_simulated_and_the_costliest_round_fit_the_budget() -> None:
    one = [[Rollout(world=0, seed=0, success=True, sim_time=6.0 / (1 + TICK_WEIGHT))]]  # 6 world-seconds
    pace = Pace(20.0)
    assert pace.fits()  # nothing simulated, no round yet
    pace.begin()
    pace.charge(one)
    pace.ended()
    for _ in range(2):  # 14 world-seconds simulated, the costliest round 6
        pace.begin()
        pace.charge(one)
        pace.ended()
    assert pace.spent == pytest.approx(18.0) and not pace.fits() and pace.ran_out
    assert Pace(20.0, spent=14.0, costliest=6.0).fits()


def test_the_search_stops_at_its_budget(task, monkeypatch: pytest.MonkeyPatch) -> None:
    """cube_lifting 10507 ran four rounds (19.7 s) and an unsolvable instance four rounds and a repair round
    (24.6 s): the rounds stop where the next would end past the budget."""
    programs = [_pushing(float(x)) for x in range(1, 9)]
    runner = ScriptedRunner({p.code: {0} for p in programs}, seconds=1.0, outcome="stalled")
    monkeypatch.setattr(search_module, "run_seeded", runner)
    # each round: one program in 3 worlds of 1 s, its longest world TICK_WEIGHT times more (the first also runs its
    # 5 fresh worlds ahead: 8 worlds)
    first, later = 8 + TICK_WEIGHT, 3 + TICK_WEIGHT
    pace = Pace(first + later + first - 0.5)  # after two rounds, the costliest round (the first) no longer fits
    _, rounds = _search(task, programs, pace)
    assert rounds == 2 and len(runner.batches) == 2 and pace.ran_out
    assert pace.spent == pytest.approx(first + later)
    _, unlimited = _search(task, programs, Pace(float("inf")))
    assert unlimited == 4


def test_a_program_that_repeats_a_refused_call_is_verified_after_one_that_does_not(
    task, monkeypatch: pytest.MonkeyPatch
) -> None:
    """cube_lifting 10507: the best guess's push of the chair was refused ("no clear place to stand behind it") in two
    of three worlds, and the next round verified three programs that pushed the chair the same way after the same
    walks, only farther: refused in the same worlds. A skill refuses from the state it starts in, so a program that
    makes the same calls up to the same skill on the same object goes after those that do not."""
    first, farther, other_way = _pushing(1.0), _pushing(1.5), _pushing(1.0, then=2.0)
    other_way.lines[0] = "p1 = get_position('crate')"  # starts otherwise: a different state at the push
    runner = ScriptedRunner({first.code: {0, 2}, farther.code: {0, 2}}, seconds=1.0)
    monkeypatch.setattr(search_module, "run_seeded", runner)
    tried, _ = _search(task, [first, farther, other_way], Pace(float("inf")))
    assert [t.program for t in tried] == [first, other_way]  # the other way held: the farther push never ran


def test_a_failed_call_other_than_a_refusal_demotes_only_the_same_call(task) -> None:
    """A push that stalled may not stall with another target: only a program making the very same call is demoted."""
    first, farther, same = _pushing(1.0), _pushing(1.5), _pushing(1.0, then=3.0)
    for outcome, demoted in (("stalled", [False, True]), ("refused", [True, True])):
        query = SkillCall(skill="get_position", args=["box"], outcome="done")
        calls = [query, SkillCall(skill=PUSH, args=[], outcome=outcome)]
        failed = Candidate(index=0, code=first.code, rollouts=[Rollout(world=0, seed=0, success=False, calls=calls)])
        prefixes = failed_prefixes([Tried(first, failed)], worlds=3)
        assert [repeats(p, prefixes) for p in (farther, same)] == demoted, outcome
    succeeded = Candidate(index=0, code=first.code, rollouts=[Rollout(world=0, seed=0, success=True, calls=calls)])
    assert failed_prefixes([Tried(first, succeeded)], worlds=3) == set()  # a world it succeeded in teaches nothing


def test_a_solution_says_when_the_budget_left_programs_unverified(task, monkeypatch: pytest.MonkeyPatch) -> None:
    runner = ScriptedRunner(None, seconds=1000.0)  # one round costs more than the whole budget
    monkeypatch.setattr(search_module, "run_seeded", runner)
    solution = solve_module.solve(task)
    assert len(runner.batches) == 1
    assert any(note.startswith("The search stopped at its budget of ") for note in solution.notes), solution.notes
