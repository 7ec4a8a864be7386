"""The four-stage DSPy program: :class:`Proposer` writes candidate programs, :class:`RoboTool` also verifies them.

:class:`Proposer` is the proposing program: the four LM stages, producing code and nothing else that is
expensive, so prompt optimisers (which see exactly its predictors) and their metric can verify a
proposal themselves (:func:`robotool.verify.select`) without running the program inside itself.
:class:`RoboTool` is the same stages followed by verified best-of-K selection; both have the same
predictors, so a state file compiled for one loads into the other.

The Analyzer runs once; the Planner, Calculator and Coder run once per candidate, concurrently,
each candidate with its own ``rollout_id``. Every stage call goes through
:func:`robotool.program.lm_calls.call_stage`: replies are parsed leniently and, when they still do not
parse, asked for again with the problem shown to the model. If the Analyzer gives no usable reply,
the candidates run without key concepts and the solution says so. Every candidate's code is
validated by the sandbox and run in ``worlds_per_candidate`` perturbed worlds, all candidates in
one batch (identical programs once); a program the sandbox rejects is asked for again like a reply
that does not parse. The candidates are ranked (see
:meth:`~robotool.solution.Candidate.rank_key`). The paper's ablations are the same module with
stages switched off: see :data:`STAGES_BY_METHOD`. Repeated runs that should sample afresh set
``rollout_base`` (candidate ``k`` uses rollout id ``rollout_base + k``). The Repair stage is a predictor of the
:class:`Proposer` too; :class:`RoboTool` with ``repair_rounds`` shows failed candidates what the simulator
measured and has them repaired (see :mod:`robotool.program.repair_rounds`).

Temperature: with ``temperature`` set, every LM call uses it; without, a single candidate uses the
model's default and several candidates spread from 0.7 to 1.0 so that they differ.
"""

from __future__ import annotations

import functools
import time
from pathlib import Path
from typing import Any, Literal, Self

import dspy

from robotool import robots
from robotool.errors import RobotoolError
from robotool.program.compiled import CompiledInfo, check_fits, read_compiled, version_note
from robotool.program.lm import DEFAULT_FORMAT_RETRIES
from robotool.program.lm_calls import CallSettings, Cancelled, PromptLog, StageFailed, call_stage, run_concurrently
from robotool.program.methods import STAGES_BY_METHOD, MethodStages, method_stages
from robotool.program.repair_rounds import RepairBudget, propose_repair, repair_rounds
from robotool.safe_text import capped, prompt_block
from robotool.sandbox import ProgramRejected, extract
from robotool.signatures import Analyze, Calculate, Code, Plan, Repair, scene_context
from robotool.solution import Candidate, CandidateFailure, LMCall, Proposal, RepairAttempt, Solution, StageOutputs
from robotool.task.describe import describe
from robotool.task.task_model import Task
from robotool.verify import chosen, prepare_code, select, verify
from robotool.vocabulary import BackendName, MethodName, Stage

AdapterName = Literal["chat", "json"]
SPREAD = (0.7, 1.0)
"""Temperatures of the first and last of several candidates when no temperature is set."""


class Proposer(dspy.Module):
    """Description -> Analyzer -> Planner -> Calculator -> Coder -> K candidate programs (not simulated)."""

    def __init__(
        self,
        *,
        analyzer: bool = True,
        planner: bool = True,
        calculator: bool = True,
        candidates: int = 1,
        temperature: float | None = None,
        rollout_base: int = 0,
        adapter: AdapterName | None = None,
        format_retries: int = DEFAULT_FORMAT_RETRIES,
        log_prompts: Path | None = None,
    ):
        """``adapter``: the answer format asked of the model (default: the one configured in DSPy, else
        field markers); ``format_retries``: repairs per stage call after an unusable reply;
        ``log_prompts``: a JSONL file that receives every request and reply."""
        super().__init__()
        if calculator and not planner:
            raise ValueError("the Calculator needs the Planner's steps")
        if candidates < 1:
            raise ValueError("candidates must be at least 1")
        if temperature is not None and temperature < 0:
            raise ValueError(f"temperature must be at least 0, got {temperature}")
        if format_retries < 0:
            raise ValueError(f"format_retries must be at least 0, got {format_retries}")
        self.analyze = dspy.Predict(Analyze) if analyzer else None
        self.plan = dspy.Predict(Plan) if planner else None
        self.calculate = dspy.Predict(Calculate) if calculator else None
        self.code = dspy.Predict(Code)
        self.repair = dspy.Predict(Repair)
        self.candidates = candidates
        self.temperature = temperature
        self.rollout_base = rollout_base
        self.adapter = adapter
        self.format_retries = format_retries
        self.log_prompts = log_prompts
        self.compiled: CompiledInfo | None = None
        self.compiled_notes: list[str] = []
        self.repair_frozen = False
        """While set, the Repair stage is not among :meth:`named_parameters` (optimisers leave it as it is)."""

    @classmethod
    def method(cls, name: str, **options: Any) -> Self:
        """The full program or an ablation by name (see :data:`STAGES_BY_METHOD`)."""
        stages = method_stages(name)
        if stages is None:
            raise ValueError(f"unknown method {name!r}; methods: {', '.join(STAGES_BY_METHOD)}")
        return cls(analyzer=stages.analyzer, planner=stages.planner, calculator=stages.calculator, **options)

    @classmethod
    def from_compiled(cls, path: Path, **options: Any) -> Self:
        """The program a compiled file was made for (its method's stages), with the file's prompts loaded.

        Raises :class:`~robotool.program.compiled.CompiledProgramError` for a file that cannot be used.
        """
        _, info = read_compiled(Path(path))
        return cls.method(info.method if info else "robotool", **options).load(path)

    def load(self, path: str | Path, allow_pickle: bool = False, allow_unsafe_lm_state: bool = False) -> Self:
        """Load a compiled program (or a DSPy state file) whose stages are this program's.

        Raises :class:`~robotool.program.compiled.CompiledProgramError` when the file cannot be read or lacks one of
        this program's stages; a file from another robotool version, or with stages this program does not
        have, loads with a note in every solution.
        """
        path = Path(path)
        state, info = read_compiled(path)
        unused = check_fits(path, state, info, [name for name, _ in self.named_predictors()])
        self.load_state(state, allow_unsafe_lm_state=allow_unsafe_lm_state)
        self.compiled = info
        self.compiled_notes = unused + ([note] if (note := version_note(path, info)) else [])
        return self

    def named_parameters(self) -> list[tuple[str, Any]]:
        """DSPy's parameters of the program, without the Repair stage while :attr:`repair_frozen` is set."""
        return [(name, p) for name, p in super().named_parameters() if not (self.repair_frozen and name == "repair")]

    @property
    def method_name(self) -> MethodName:
        stages = MethodStages(
            analyzer=self.analyze is not None, planner=self.plan is not None, calculator=self.calculate is not None
        )
        return next(name for name, switches in STAGES_BY_METHOD.items() if switches == stages)

    def forward(self, task: Task) -> dspy.Prediction:
        """Propose candidate programs for ``task``; the prediction carries the :class:`Proposal`.

        Raises :class:`~robotool.errors.LMUnavailableError` when the model cannot be used at all.
        """
        started = time.perf_counter()
        description = prompt_block(describe(task))
        settings = self._call_settings()
        shared = StageOutputs()
        notes: list[str] = list(self.compiled_notes)
        analyzer_calls: list[LMCall] = []
        if self.analyze is not None:
            try:
                with scene_context(task, robots.get(task.embodiment)):
                    result = call_stage(
                        self.analyze,
                        "analyzer",
                        {"description": description},
                        settings=settings,
                        config=self._config(None),
                    )
                shared = StageOutputs(analysis=result.outputs.analysis, key_concepts=result.outputs.key_concepts)
                analyzer_calls = result.calls
                notes += [f"analyzer: {note}" for note in result.notes]
            except StageFailed as e:
                analyzer_calls = e.calls
                notes.append(f"the Analyzer gave no usable reply ({e.reason}); the candidates ran without key concepts")
            except RobotoolError:
                raise
            except Exception as e:  # a fault in the Analyzer leaves the candidates to run without it
                notes.append(
                    f"the Analyzer failed ({type(e).__name__}: {capped(' '.join(str(e).split()), 300)}); the "
                    "candidates ran without key concepts"
                )
        lm_started = time.perf_counter()
        candidates = self._sample(task, description, shared, settings)
        proposal = Proposal(
            task=task.name,
            method=self.method_name,
            shared=shared,
            candidates=candidates,
            lm_calls=analyzer_calls,
            notes=notes,
            timings={"analyzer": lm_started - started, "candidates": time.perf_counter() - lm_started},
        )
        return dspy.Prediction(proposal=proposal)

    def repair_candidate(
        self, task: Task, source: Candidate, index: int, sampled: int, settings: CallSettings
    ) -> tuple[Candidate, RepairAttempt]:
        """The Repair stage's fix of the failed candidate ``source`` as candidate ``index``, sampled like the
        proposed candidate ``sampled`` (see :func:`robotool.program.repair_rounds.propose_repair`); not simulated."""
        return propose_repair(
            self.repair,
            task,
            prompt_block(describe(task)),
            source,
            index,
            settings=settings,
            config=self._config(sampled),
            salvage=_program_reply,
        )

    def _call_settings(self) -> CallSettings:
        """How every stage call of one solve is made (a fresh cancellation flag each time)."""
        return CallSettings(
            adapter=self._adapter(),
            format_retries=self.format_retries,
            log=PromptLog(self.log_prompts) if self.log_prompts else None,
        )

    def _adapter(self) -> dspy.Adapter:
        """The adapter of every stage call; DSPy's one-shot JSON fallback is off (repairs replace it)."""
        if self.adapter == "json":
            return dspy.JSONAdapter()
        if self.adapter is None and dspy.settings.adapter is not None:
            return dspy.settings.adapter
        return dspy.ChatAdapter(use_json_adapter_fallback=False)

    def _sample(self, task: Task, description: str, shared: StageOutputs, settings: CallSettings) -> list[Candidate]:
        """Run the per-candidate stages for every candidate concurrently."""
        return run_concurrently(
            [functools.partial(self._candidate, task, description, shared, k, settings) for k in range(self.candidates)]
        )

    def _config(self, k: int | None) -> dict[str, Any]:
        """Sampling settings of candidate ``k`` (None: the Analyzer)."""
        config: dict[str, Any] = {}
        if self.temperature is not None:
            config["temperature"] = self.temperature
        elif k is not None and self.candidates > 1:
            low, high = SPREAD
            config["temperature"] = low + (high - low) * k / (self.candidates - 1)
        if k is not None and self.candidates > 1 and config.get("temperature", 0) > 0:
            config["rollout_id"] = self.rollout_base + k
        return config

    def _candidate(
        self, task: Task, description: str, shared: StageOutputs, k: int, settings: CallSettings
    ) -> Candidate:
        candidate = Candidate(index=k, stages=shared.model_copy())
        stages, config = candidate.stages, self._config(k)
        concepts = shared.key_concepts or []

        def run(predictor: dspy.Predict, stage: Stage, inputs: dict[str, Any], **reading: Any) -> dspy.Prediction:
            result = call_stage(predictor, stage, inputs, settings=settings, candidate=k, config=config, **reading)
            candidate.lm_calls += result.calls
            candidate.notes += [f"{stage}: {note}" for note in result.notes]
            return result.outputs

        def program_problem(out: dspy.Prediction) -> str | None:
            """Why the Coder's program cannot run (shown to the model), keeping the last program seen."""
            candidate.code, rejection, dropped = prepare_code(out.code, task)
            if dropped and f"coder: {dropped}" not in candidate.notes:
                candidate.notes.append(f"coder: {dropped}")
            return rejection

        stage: Stage = "planner"
        try:
            with scene_context(task, robots.get(task.embodiment)):
                if self.plan is not None:
                    out = run(self.plan, stage, {"description": description, "key_concepts": concepts})
                    stages.object_roles, stages.abstract_plan, stages.steps = (
                        out.object_roles or [],
                        out.abstract_plan or "",
                        out.steps,
                    )
                stage = "calculator"
                if self.calculate is not None:
                    out = run(
                        self.calculate,
                        stage,
                        {"description": description, "key_concepts": concepts, "steps": stages.steps},
                    )
                    stages.calculation, stages.parameters = out.calculation or "", out.parameters
                stage = "coder"
                out = run(
                    self.code,
                    stage,
                    {"description": description, "steps": stages.steps or [], "parameters": stages.parameters or []},
                    salvage=_program_reply,
                    check=program_problem,
                )
        except StageFailed as e:
            candidate.lm_calls += e.calls
            candidate.failure = CandidateFailure(stage=stage, kind="no_reply", reason=e.reason)
            return candidate
        except (RobotoolError, Cancelled):
            raise
        except Exception as e:  # a fault in this candidate's stage must not end the others
            reason = f"{type(e).__name__}: {capped(' '.join(str(e).split()), 300)}"
            candidate.failure = CandidateFailure(stage=stage, kind="fault", reason=reason)
        return candidate


class RoboTool(Proposer):
    """The :class:`Proposer`'s candidates, verified in ``worlds_per_candidate`` perturbed worlds each; the best wins."""

    def __init__(
        self,
        *,
        worlds_per_candidate: int = 3,
        backend: BackendName | None = None,
        seed: int = 0,
        repair_rounds: int = 0,
        repair_tokens: int | None = None,
        **proposer: Any,
    ):
        """``proposer``: the :class:`Proposer`'s options (stages, candidates, sampling, answer format);
        ``repair_rounds``: rounds in which, while no candidate succeeds in every world, the best ``candidates``
        failures are repaired from their simulator traces (see :mod:`robotool.program.repair_rounds`);
        ``repair_tokens``: no repair round starts once repairs have used this many tokens."""
        super().__init__(**proposer)
        if worlds_per_candidate < 1:
            raise ValueError("worlds_per_candidate must be at least 1")
        if repair_rounds < 0:
            raise ValueError(f"repair_rounds must be at least 0, got {repair_rounds}")
        if repair_tokens is not None and repair_tokens < 1:
            raise ValueError(f"repair_tokens must be at least 1, got {repair_tokens}")
        self.worlds_per_candidate = worlds_per_candidate
        self.backend = backend
        self.seed = seed
        self.repair_budget = RepairBudget(rounds=repair_rounds, width=self.candidates, tokens=repair_tokens)

    def forward(self, task: Task) -> dspy.Prediction:
        """Solve ``task``; the prediction carries the :class:`Solution` and the best code.

        Raises :class:`~robotool.errors.LMUnavailableError` when the model cannot be used at all.
        """
        proposal = super().forward(task).proposal
        solution = select(task, proposal, worlds=self.worlds_per_candidate, seed=self.seed, backend=self.backend)
        if self.repair_budget.rounds:
            solution = self._repaired(task, proposal, solution)
        return dspy.Prediction(solution=solution, code=solution.code)

    def _repaired(self, task: Task, proposal: Proposal, solution: Solution) -> Solution:
        """``solution`` after repair rounds over its verified candidates (unchanged when none ran)."""
        started = time.perf_counter()
        candidates = list(solution.candidates)
        settings = self._call_settings()

        def propose(source: Candidate, index: int) -> tuple[Candidate, RepairAttempt]:
            sampled = source  # a repair samples like the candidate its line of repairs began with
            while sampled.repaired_from is not None:
                sampled = next(c for c in candidates if c.index == sampled.repaired_from)
            return self.repair_candidate(task, source, index, sampled.index, settings)

        def check(new: list[Candidate]) -> None:
            verify(task, new, worlds=self.worlds_per_candidate, seed=self.seed, backend=self.backend)

        rounds = repair_rounds(candidates, propose, check, self.repair_budget)
        if not rounds:
            return solution
        timings = {k: v for k, v in solution.timings.items() if k != "total"}
        repaired = chosen(proposal, candidates, timings | {"repair": time.perf_counter() - started})
        repaired.repairs = rounds
        return repaired


def _program_reply(text: str) -> dspy.Prediction:
    """The Coder's output from a plain chat answer (prose and code blocks): the answer itself, which the stage's
    check extracts the program from (noting which block it chose, or why the code does not parse); raises
    :class:`~robotool.sandbox.ProgramRejected` (a ValueError) when it holds no program at all."""
    try:
        extract(text)
    except ProgramRejected as e:
        if e.construct == "text":  # no program: the reply's format is what was wrong
            raise
    return dspy.Prediction(code=text)
