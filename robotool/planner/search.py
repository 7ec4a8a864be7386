"""Generate-and-test: order candidate programs, verify them in the batched simulator round by round.

Programs are ordered by what the planner predicts from geometry (predicted-feasible first), then by how many
objects they use, then stances with slack before tight ones, then by how many motion steps they take; each round
verifies the next ``beam`` of them (from one tier: tool-free programs come as their own first tier when the
geometry says no tool is needed) in one batch of perturbed worlds (the first round may verify fewer: the best guess
alone costs least when it holds). A program that succeeds in every one of these planning worlds is then run in
``verify`` fresh perturbed worlds, whose seeds the planning worlds never use (:func:`verification_seed`); its
rollouts are the planning and the fresh worlds together, so one that fails a fresh world no longer counts as
succeeding everywhere and ranks below one that held in all of them. The first round's best guess runs in its fresh
worlds in the same batch as its planning worlds (most often it holds, and one batch of eight worlds costs much less
than two of three and five: the controller's tick costs nearly as much for few worlds as for many), unless it is
predicted to fail (every program is, then); those fresh rollouts count only if it held in every planning world.
When the first round holds nothing, programs the caller makes from its failures (the planner's variants of a near miss)
join the second round. A program that pushes an object some program's push found too heavy on its own in a planning
world is not verified (:func:`too_heavy`: a seed makes the same world in every batch, so its push is refused there, and
a planner's program pushes an object only to use it or to clear it away). A program that starts as a tried one did up to
a call that failed in a planning world (:func:`repeats`) is verified after the programs as likely by prediction that do
not. The search stops at the first round with a program that succeeded in every planning and fresh world (or when the
rounds run out, or the next round would not fit the budget of simulated world-seconds: :class:`Pace`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from robotool.planner.codegen import Program
from robotool.rollout import Rollout
from robotool.solution import Candidate, CandidateFailure, StageOutputs
from robotool.task.task_model import Task
from robotool.verify import failure_reason, prepare_code, run_seeded
from robotool.vocabulary import BackendName


@dataclass(frozen=True)
class Budget:
    """How much verifying one search may do."""

    beam: int  # programs per round (one simulator batch)
    rounds: int  # rounds at most
    work: float  # world-seconds to simulate at most: a round starts only when it is likely to end within them (Pace)
    first: int | None = None  # programs in the first round (default: beam)
    verify: int = 0  # fresh worlds a program that held in every planning world must also hold in
    doubted_rounds: int | None = None  # rounds at most while every program run was doubted and none succeeded anywhere


TICK_WEIGHT = 3.0
"""A batch's controller ticks, made for all its worlds at once for as long as its longest world runs, cost about as
much as the physics of this many worlds (measured on a legged robot's planning batches of 5 to 15 worlds)."""


def work(results: Sequence[Sequence[Rollout]]) -> float:
    """What simulating one batch cost, in world-seconds: the simulated seconds of its worlds, summed, and its longest
    world's :data:`TICK_WEIGHT` times more (proportional to the batch's time on any one machine, within about 10 %)."""
    times = [rollout.sim_time for rollouts in results for rollout in rollouts]
    return sum(times) + TICK_WEIGHT * max(times, default=0.0)


@dataclass
class Pace:
    """What a planning run has simulated and its costliest round so far, in world-seconds (:func:`work`): a round
    starts only when what was simulated plus the costliest round fits in ``budget`` (a round costs about as much as
    the rounds before it), so that the run ends near its budget rather than a round past it. Counted in simulated
    time, not on a clock, so that a task plans the same way on a busy machine as on an idle one."""

    budget: float
    spent: float = 0.0
    costliest: float = 0.0
    ran_out: bool = False  # a round did not start for want of budget
    _began: float = 0.0  # what was simulated when the round under way began

    def fits(self) -> bool:
        """Whether one more round is likely to end within the budget (when not, :attr:`ran_out` is set)."""
        self.ran_out |= self.spent + self.costliest > self.budget
        return not self.ran_out

    def begin(self) -> None:
        """A round begins."""
        self._began = self.spent

    def charge(self, results: Sequence[Sequence[Rollout]]) -> None:
        """Count one simulated batch toward the run (and the round under way)."""
        self.spent += work(results)

    def ended(self) -> None:
        """The round begun last ended."""
        self.costliest = max(self.costliest, self.spent - self._began)


VERIFY_OFFSET = 10_000  # verification world seeds start this far from the planning seed


def verification_seed(seed: int, worlds: int) -> int:
    """First world seed of the verification worlds: past every planning world seed (``seed`` to
    ``seed + worlds - 1``), so the fresh worlds are never planning worlds."""
    return seed + max(VERIFY_OFFSET, worlds)


def held(candidate: Candidate) -> bool:
    """Whether a candidate ran and succeeded in every one of its worlds."""
    return bool(candidate.rollouts) and candidate.success_rate == 1.0


@dataclass
class Tried:
    """One verified (or rejected) program and its candidate record."""

    program: Program
    candidate: Candidate


TIGHT = 0.02  # m: a program whose tightest stance keeps less than this from an edge is tight (perturbations undo it)


def order(programs: Iterable[Program]) -> list[Program]:
    """Distinct programs, best guess first: predicted feasible, then fewer less likely choices, then fewer objects,
    then not tight (:func:`tight`: a stance with little slack, or a push near the mass limit, fails in some perturbed
    worlds; but every object more to push is a bigger risk), then fewer steps."""
    seen: set[str] = set()
    unique = []
    for prog in programs:
        if prog.code not in seen:
            seen.add(prog.code)
            unique.append(prog)
    return sorted(unique, key=lambda p: (*precedence(p), tight(p), len(p.steps)))


def precedence(prog: Program) -> tuple[bool, int, int]:
    """What :func:`order` weighs before a program's margins: predicted to fail, its less likely choices, its
    objects."""
    return prog.doubt is not None, prog.late, len(prog.objects)


def tight(prog: Program) -> bool:
    """Whether a program leaves a margin that perturbed worlds may undo: a stance within :data:`TIGHT` of an edge,
    or another margin the macros found thin (an object to push whose mass may exceed the push limit)."""
    return prog.slack < TIGHT or bool(prog.thin)


PUSH = "push_to_position"


def too_heavy(tried: Iterable[Tried], worlds: int) -> dict[str, int]:
    """The objects a push was refused for in a planning world because of their own mass (nothing riding on them or
    stuck to them), each with the first such world (its index among the ``worlds`` planning worlds). A seed makes the
    same world in every batch, so any program that pushes one of them is refused that push in that world (and a
    planner's program pushes an object only to use it or to clear it away: it does not hold)."""
    heavy: dict[str, int] = {}
    for item in tried:
        for k, rollout in enumerate(item.candidate.rollouts[:worlds]):
            for call in rollout.calls:
                measured = call.measured
                refused = call.skill == PUSH and call.outcome == "refused" and bool(call.args)
                alone = measured.get("riders") == measured.get("stuck") == 0.0  # nothing rode on it or stuck to it
                own_mass = alone and measured.get("mass", 0.0) > measured.get("limit", 1e9)
                if refused and own_mass:
                    heavy.setdefault(str(call.args[0]), k)
    return heavy


def failed_prefixes(tried: Iterable[Tried], worlds: int) -> set[str]:
    """The texts of tried programs up to the first call that did not end done in a planning world they failed, and
    that call (:meth:`~robotool.planner.codegen.Program.reaching_call`): whole, or as far as its object where it was
    refused. A program that starts with one comes to that call in that world in the same state, and makes it again
    there (a skill refuses from the state it starts in, whatever its target: the same skill on the same object is
    likely refused again); it is likely to fail that world the same way."""
    prefixes = set()
    for item in tried:
        for rollout in item.candidate.rollouts[:worlds]:
            failed = next((k for k, call in enumerate(rollout.calls) if call.outcome != "done"), None)
            if rollout.success or failed is None:
                continue
            prefix = item.program.reaching_call(failed, whole=rollout.calls[failed].outcome != "refused")
            if prefix is not None:
                prefixes.add(prefix)
    return prefixes


def repeats(program: Program, prefixes: set[str]) -> bool:
    """Whether ``program`` starts as a tried program did up to a call that failed in a planning world
    (:func:`failed_prefixes`): it is verified after those as likely to hold by prediction that do not."""
    code = program.code
    return any(code.startswith(prefix) for prefix in prefixes)


def doomed(program: Program, heavy: dict[str, int]) -> str | None:
    """The object ``program`` pushes that a planning world made too heavy to push (:func:`too_heavy`), so that it
    cannot succeed in every planning world, or None."""
    return next((m.obj for m in program.motions if m.skill == PUSH and m.obj in heavy), None)


FollowUp = Callable[[list[Tried]], list[tuple[Program, Tried]]]
"""Programs made from the first round's failures (each with the failure it came from), verified in the second."""


def search(
    task: Task,
    tiers: list[list[Program]],
    stages: Callable[[Program], StageOutputs],
    *,
    worlds: int,
    seed: int,
    backend: BackendName | None,
    budget: Budget,
    start: int = 0,
    follow_up: FollowUp | None = None,
    pace: Pace | None = None,
) -> tuple[list[Tried], int]:
    """Verify programs in rounds, tier by tier (a round never mixes tiers; each tier already ordered).

    Candidates are numbered from ``start``. When nothing held in the first round (the best guess, when the budget
    runs it alone), ``follow_up`` may make programs from its failures: they join the second round after its own
    programs (as candidates ``repaired_from`` their sources), or make a round of their own when no program is left.
    ``pace`` counts what a planning run that searches more than once simulates (default: this search's own, from
    ``budget.work``). Returns what was tried and how many rounds ran."""
    pace = pace or Pace(budget.work)
    tried: list[Tried] = []
    rounds = 0
    queue = [(k, p) for k, tier in enumerate(tiers) for p in tier]
    taken = 0  # programs of the queue verified so far
    carried: list[tuple[Program, Tried]] = []
    while rounds < budget.rounds and (taken < len(queue) or carried):
        if not pace.fits():
            break
        pace.begin()
        size = budget.beam if rounds or budget.first is None else budget.first
        heavy, prefixes = too_heavy(tried, worlds), failed_prefixes(tried, worlds)
        left = [(t, p) for t, p in queue[taken:] if doomed(p, heavy) is None]
        queue[taken:] = sorted(left, key=lambda tp: (tp[0], precedence(tp[1]), repeats(tp[1], prefixes)))
        carried = [(p, source) for p, source in carried if doomed(p, heavy) is None]
        if taken == len(queue) and not carried:
            break
        tier = queue[taken][0] if taken < len(queue) else None
        own = [p for t, p in queue[taken : taken + size] if t == tier]
        taken += len(own)
        batch = [Tried(p, Candidate(index=start + len(tried) + k, stages=stages(p))) for k, p in enumerate(own)]
        for program, source in carried:
            made = Candidate(index=start + len(tried) + len(batch), stages=stages(program))
            mark_repaired(made, source.candidate)
            batch.append(Tried(program, made))
        carried = []
        runnable, codes = [], []
        for item in batch:
            item.candidate.code, rejection, _ = prepare_code(item.program.code, task)
            if rejection is not None:
                item.candidate.failure = CandidateFailure(stage="search", kind="rejected", reason=rejection)
            elif item.candidate.code is not None:  # always, without a rejection
                runnable.append(item)
                codes.append(item.candidate.code)
        planning = range(seed, seed + worlds)
        fresh = range(verification_seed(seed, worlds), verification_seed(seed, worlds) + budget.verify)
        # the best guess's fresh worlds, in this batch (not for one predicted to fail: it seldom holds)
        ahead = bool(budget.verify) and not rounds and bool(codes) and runnable[0].program.doubt is None
        runs = [(code, [*planning, *fresh] if ahead and k == 0 else planning) for k, code in enumerate(codes)]
        results = run_seeded(task, runs, backend=backend)
        pace.charge(results)
        for item, rollouts in zip(runnable, results, strict=True):
            item.candidate.rollouts = rollouts[:worlds]
            item.candidate.failure = failure_reason(item.candidate.rollouts)
        if budget.verify:
            confirm(
                task,
                [t.candidate for t in runnable],
                worlds=budget.verify,
                seed=fresh.start,
                backend=backend,
                ran={runnable[0].candidate.index: results[0][worlds:]} if ahead else {},
                pace=pace,
            )
        tried += batch
        rounds += 1
        pace.ended()
        if any(held(t.candidate) for t in batch) or hopeless(tried, rounds, budget):
            break
        if follow_up is not None and rounds == 1:
            carried = follow_up(batch)
    return tried, rounds


def mark_repaired(candidate: Candidate, source: Candidate) -> None:
    """Record that ``candidate`` was re-parameterised from ``source``."""
    candidate.repaired_from = source.index
    candidate.notes.append(f"re-parameterised from candidate {source.index}")


def hopeless(tried: list[Tried], rounds: int, budget: Budget) -> bool:
    """Whether the search stops early (and the planner repairs nothing): ``budget.doubted_rounds`` rounds have run,
    every program in them was predicted to break a limit and none succeeded in any world (those left are doubted too:
    doubted programs come last)."""
    return (
        budget.doubted_rounds is not None
        and rounds >= budget.doubted_rounds
        and all(t.program.doubt is not None for t in tried)
        and not any(r.success for t in tried for r in t.candidate.rollouts)
    )


def confirm(
    task: Task,
    candidates: list[Candidate],
    *,
    worlds: int,
    seed: int,
    backend: BackendName | None,
    pace: Pace,
    ran: dict[int, list[Rollout]] | None = None,
) -> None:
    """Run the candidates that held in every world, in order, in ``worlds`` fresh worlds from ``seed`` until one
    holds in all of them too; the fresh rollouts join each one's own (and its failure reason is updated), and ``pace``
    counts their runs. ``ran``: fresh rollouts already run, by candidate index (their seeds these same ones), used
    instead of running again."""
    for candidate in candidates:
        if not held(candidate):
            continue
        assert candidate.code is not None
        fresh = (ran or {}).get(candidate.index)
        if fresh is None:
            fresh = run_seeded(task, [(candidate.code, range(seed, seed + worlds))], backend=backend)[0]
            pace.charge([fresh])
        planned = len(candidate.rollouts)  # the fresh worlds are numbered after the planning ones (seeds say which)
        candidate.rollouts += [r.model_copy(update={"world": planned + k}) for k, r in enumerate(fresh)]
        candidate.failure = failure_reason(candidate.rollouts)
        candidate.notes.append(
            f"verified in {worlds} fresh perturbed worlds (seeds {seed}-{seed + worlds - 1}): "
            f"succeeded in {sum(r.success for r in fresh)}"
        )
        if held(candidate):
            return
