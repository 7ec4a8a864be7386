"""Prompt optimisation: examples, the simulator-verified metric and its feedback for each stage, the
optimisers end to end (scripted LMs, labelled test fixtures, and the HTTP stand-in), planner
demonstrations and compiled programs in solve, eval and RoboTool.load."""

from __future__ import annotations

import json
from pathlib import Path

import dspy
import pytest
from fixtures.optimize_lm import ReflectionEngine, RoutingEngine, engine_lm
from fixtures.scripted_lm import (
    CLIMB_DIRECTLY,
    GRASP_DIRECTLY,
    STAGE_MARKERS,
    STAND_STILL,
    ScriptedEngine,
    arm_script,
    quadruped_script,
)

from robotool import tasks
from robotool.eval.reference import PAPER_TASKS
from robotool.optimize import Metric, OptimizeSettings, RolloutBatcher, optimize
from robotool.optimize.data import DatasetError, Splits, builtin, check_training, splits
from robotool.optimize.feedback import concept_findings
from robotool.program.compiled import CompiledProgramError
from robotool.program.lm import make_lm
from robotool.program.lm_program import Proposer, RoboTool
from robotool.program.standin import Rule, Script, StandinServer
from robotool.signatures import Repair
from robotool.solution import Candidate, CandidateFailure, Proposal
from robotool.task.concepts import KeyConcept
from robotool.verify import run_codes, select

ARM, QUADRUPED = "milk_reaching_near", "sofa_climbing_low_sofa"
CHAT = dspy.ChatAdapter(use_json_adapter_fallback=False)


def _task_lm(arm_code: str = GRASP_DIRECTLY) -> tuple[dspy.LM, RoutingEngine]:
    engine = RoutingEngine({"sofa": ScriptedEngine(quadruped_script([CLIMB_DIRECTLY])),
                            "milk": ScriptedEngine(arm_script([arm_code]))})
    return engine_lm(engine), engine


def _settings(optimizer: str, **budget: int) -> OptimizeSettings:
    return OptimizeSettings(optimizer=optimizer, families=["milk_reaching"], train=2, val=1, worlds=1, threads=2,
                    budget=budget or {})


def _verified(task_name: str, code: str, *, failed_stage: str | None = None) -> tuple[dspy.Example, object]:
    gold = builtin(task_name)
    proposal = Proposal(task=task_name, method="coder",
                        candidates=[Candidate(index=0, code=code, failure=CandidateFailure(
                            stage=failed_stage, kind="no_reply", reason="rejected") if failed_stage else None)])
    return gold, select(gold.task, proposal, worlds=1)


# -- examples -------------------------------------------------------------------------------------


def test_splits_are_disjoint_and_hold_the_paper_tasks_out_of_training() -> None:
    data = splits(["sofa_climbing", "milk_reaching"], train=3, val=2, test=1)
    keys = [{(e.family, e.seed) for e in part} for part in (data.train, data.val, data.test)]
    assert not (keys[0] & keys[1] or keys[0] & keys[2] or keys[1] & keys[2])
    assert {e.name for e in data.test} >= set(PAPER_TASKS)
    assert all(e.key_concepts and e.needs_tool is not None for e in data.train)
    with pytest.raises(DatasetError, match="held out of training"):
        check_training([builtin("milk_reaching")])
    with pytest.raises(DatasetError, match="belongs to the val split"):
        check_training(data.val)


# -- the metric and its feedback --------------------------------------------------------------------


def test_metric_verifies_once_and_gives_plain_optimisers_the_score() -> None:
    lm, _ = _task_lm()
    with dspy.context(lm=lm, adapter=CHAT):
        pred = Proposer()(task=tasks.load(ARM))
    metric = Metric(worlds=2, batcher=RolloutBatcher(window=0.0))
    gold = builtin(ARM)
    assert metric(gold, pred) == 1.0
    scored = metric(gold, pred, None, "plan", None)
    assert scored.score == 1.0 and "2 of 2" in scored.feedback
    assert metric.batcher.batches == [1]  # GEPA's per-predictor call reused the verdict
    with pytest.raises(TypeError, match="compile a Proposer"):
        metric(gold, dspy.Prediction(solution=None))


def test_feedback_to_the_analyzer_names_the_missed_and_misjudged_quantities() -> None:
    truth = [KeyConcept(name="height to climb from ground onto sofa", kind="climb_height", value=0.3, limit=0.12,
                        limit_name="max_step_up", satisfied=False)]
    misjudged = [truth[0].model_copy(update={"satisfied": True})]
    misread = [truth[0].model_copy(update={"value": 0.1})]
    assert "misjudged the limit" in concept_findings(truth, misjudged)[0].text
    assert "you gave 0.1 m" in concept_findings(truth, misread)[0].text
    other = [KeyConcept(name="gap", kind="gap_width", value=0.2, limit=0.1, limit_name="max_gap", satisfied=False)]
    assert "missed a deciding quantity: height to climb" in concept_findings(truth, other)[0].text
    assert concept_findings(truth, truth) == []


def test_feedback_to_the_planner_on_a_missing_tool() -> None:
    gold, solution = _verified("milk_reaching", GRASP_DIRECTLY)
    feedback = Metric(worlds=1).feedback(gold, solution, "plan")
    assert "needs a tool but the program used none of hammer" in feedback
    assert "Nothing points at the Coder" in Metric(worlds=1).feedback(gold, solution, "code")


def test_feedback_to_the_planner_on_a_refused_step() -> None:
    gold, solution = _verified(QUADRUPED, "push_to_position('sofa', [0.0, 0.0, 0.0])\n")
    feedback = Metric(worlds=1).feedback(gold, solution, "plan")
    assert "push_to_position('sofa'" in feedback and "was refused" in feedback


def test_feedback_to_the_calculator_on_a_clamped_target_with_the_measured_distance() -> None:
    code = "open_gripper()\nmove_to_position([0.9, 0.0, 0.1])\nclose_gripper()\n"
    gold, solution = _verified(ARM, code)
    feedback = Metric(worlds=1).feedback(gold, solution, "calculate")
    assert "move_to_position([0.9, 0.0, 0.1])" in feedback and "outside_workspace 0.450" in feedback


def test_feedback_to_the_coder_on_a_refused_program_and_a_program_that_raises() -> None:
    gold, solution = _verified(ARM, "x = 1\nimport os\n", failed_stage="coder")
    assert "the sandbox refused the program at line 2" in Metric(worlds=1).feedback(gold, solution, "code")
    gold, solution = _verified(ARM, "open_gripper()\nx = 1 / 0\n")
    assert "ZeroDivisionError" in Metric(worlds=1).feedback(gold, solution, "code")


# -- batching -----------------------------------------------------------------------------------------


def test_concurrent_verifications_share_one_batch_and_get_their_own_worlds() -> None:
    from concurrent.futures import ThreadPoolExecutor

    task = tasks.load(ARM)
    batcher = RolloutBatcher(window=0.2)
    codes = [GRASP_DIRECTLY, STAND_STILL, GRASP_DIRECTLY]
    with ThreadPoolExecutor(3) as pool:
        merged = list(pool.map(lambda c: batcher(task, [c], worlds=2, seed=5), codes))
    assert batcher.batches == [3]
    alone = run_codes(task, [STAND_STILL], worlds=2, seed=5)
    assert [r.model_dump() for r in merged[1][0]] == [r.model_dump() for r in alone[0]]
    assert [[r.success for r in m[0]] for m in merged] == [[True, True], [False, False], [True, True]]


# -- optimisers --------------------------------------------------------------------------------------


def test_bootstrap_fewshot_on_two_training_examples(tmp_path: Path) -> None:
    lm, _ = _task_lm()
    data = Splits(train=[builtin(ARM), builtin(QUADRUPED)], val=[builtin(ARM)], test=[])
    with dspy.context(adapter=CHAT):
        outcome = optimize(_settings("bootstrap", demos=2), out=tmp_path / "p.json", log=tmp_path / "log", lm=lm,
                           data=data, say=lambda _: None)
    assert outcome.info.validation.before == outcome.info.validation.after == 1.0
    program = RoboTool.from_compiled(tmp_path / "p.json")
    demos = [d["code"] for d in program.code.demos]
    assert len(demos) == 2
    assert any(GRASP_DIRECTLY.strip() in d for d in demos) and any(CLIMB_DIRECTLY.strip() in d for d in demos)


def test_bootstrap_sees_no_repair_stage_and_says_when_it_kept_no_demonstration(tmp_path: Path, monkeypatch) -> None:
    lm, _ = _task_lm(arm_code=STAND_STILL)  # the arm task fails in every world: nothing to keep
    seen: list[list[str]] = []
    original = dspy.BootstrapFewShot.compile

    def compile_watched(self, student, **kwargs):
        seen.append([name for name, _ in student.named_predictors()])
        return original(self, student, **kwargs)

    monkeypatch.setattr(dspy.BootstrapFewShot, "compile", compile_watched)
    said: list[str] = []
    data = Splits(train=[builtin(ARM)], val=[], test=[])
    with dspy.context(adapter=CHAT):
        outcome = optimize(_settings("bootstrap", demos=2), out=tmp_path / "p.json", log=tmp_path / "log", lm=lm,
                           data=data, say=said.append)
    assert seen == [["analyze", "plan", "calculate", "code"]]  # the metric never runs repair rounds
    assert any("bootstrap kept no demonstration" in line for line in said)
    assert any("kept no demonstration" in note for note in outcome.info.notes)
    program = RoboTool.from_compiled(tmp_path / "p.json")  # the file still holds every stage, Repair as it was
    assert program.repair.signature.instructions == Repair.instructions and program.compiled.train == [ARM]


def test_mipro_on_two_training_examples_sets_the_proposed_instruction(tmp_path: Path, capfd) -> None:
    lm, engine = _task_lm()
    reflection = ReflectionEngine("Always query positions right before every motion (MIPRO-PROPOSED).")
    data = Splits(train=[builtin(ARM), builtin(QUADRUPED)], val=[builtin(ARM)], test=[])
    with dspy.context(adapter=CHAT):
        optimize(_settings("mipro", trials=2, candidates=2, demos=1), out=tmp_path / "p.json", log=tmp_path / "log",
                 lm=lm, reflection_lm=engine_lm(reflection), data=data, say=lambda _: None)
    assert any("MIPRO-PROPOSED" in s for s in engine.systems)
    stored = json.loads((tmp_path / "p.json").read_text())
    assert stored["robotool"]["optimizer"] == "mipro" and set(stored) >= {"analyze", "plan", "calculate", "code"}
    # the metric never runs repair rounds: the Repair stage is frozen, stored as it was
    assert stored["repair"]["signature"]["instructions"] == Repair.instructions and not stored["repair"]["demos"]
    shown = capfd.readouterr()  # DSPy's trial lines and progress bars went to the log file, not the console
    assert "Trial" not in shown.err + shown.out and "Average Metric" not in shown.err + shown.out
    assert "Trial" in (tmp_path / "log" / "dspy.log").read_text()


class _ProseProposer:
    """TEST FIXTURE: an optimiser's model that answers in prose, never in the fields asked for."""

    def complete(self, request):
        from fixtures.optimize_lm import _response

        return _response(request, "I think the instruction should be clearer. Sorry, I cannot format this.")


def test_mipro_survives_a_proposer_reply_it_cannot_read_with_a_note(tmp_path: Path) -> None:
    lm, _ = _task_lm()
    data = Splits(train=[builtin(ARM), builtin(QUADRUPED)], val=[builtin(ARM)], test=[])
    said: list[str] = []
    with dspy.context(adapter=CHAT):
        outcome = optimize(_settings("mipro", trials=2, candidates=2, demos=1), out=tmp_path / "p.json",
                           log=tmp_path / "log", lm=lm, reflection_lm=engine_lm(_ProseProposer()), data=data,
                           say=said.append)
    assert any("mipro: the proposer's reply could not be read" in line for line in said)
    assert "mipro: the default program is evaluated, then 2 trial(s) of proposed prompts" in said
    assert any("stages keep their instructions" in note for note in outcome.info.notes)
    program = RoboTool.from_compiled(tmp_path / "p.json")
    assert program.code.signature.instructions == Proposer().code.signature.instructions


def test_simba_on_two_training_examples(tmp_path: Path) -> None:
    lm, _ = _task_lm(arm_code=STAND_STILL)
    data = Splits(train=[builtin(ARM), builtin(QUADRUPED)], val=[], test=[])
    with dspy.context(adapter=CHAT):
        optimize(_settings("simba", steps=1, candidates=2, demos=1), out=tmp_path / "p.json", log=tmp_path / "log",
                 lm=lm, reflection_lm=engine_lm(ReflectionEngine("unused")), data=data, say=lambda _: None)
    assert RoboTool.from_compiled(tmp_path / "p.json").compiled.optimizer == "simba"


def _standin_rules(coder_code: str) -> list[Rule]:
    script = arm_script([coder_code])
    return [Rule(match=marker, reply=script[stage][0]) for stage, marker in STAGE_MARKERS.items()]


def test_gepa_over_http_puts_the_reflected_instruction_into_the_prompts(tmp_path: Path) -> None:
    marker = "GEPA-PROPOSED: first check that the milk's graspable point is inside the workspace."
    reflection = ReflectionEngine(marker)
    data = Splits(train=[builtin(ARM)], val=[builtin(ARM)], test=[])
    with StandinServer(Script(rules=_standin_rules(STAND_STILL))) as server, dspy.context(adapter=CHAT):
        lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=0)
        outcome = optimize(_settings("gepa", max_metric_calls=6), out=tmp_path / "p.json", log=tmp_path / "log",
                           lm=lm, reflection_lm=engine_lm(reflection), data=data, say=lambda _: None)
        systems = [m["content"] for r in server.requests for m in r["messages"] if m["role"] == "system"]
    assert any(marker in s for s in systems)
    shown = "\n".join(reflection.shown)
    assert "perturbed simulated world" in shown and "a step is missing: no motion was made" in shown
    assert outcome.info.validation.before == 0.0
    assert (tmp_path / "log" / "gepa").is_dir()


def test_gepa_with_a_scripted_lm_reflects_on_each_stage_s_feedback(tmp_path: Path) -> None:
    marker = "GEPA-PROPOSED: move the gripper to the milk before closing it."
    lm, engine = _task_lm(arm_code=STAND_STILL)
    reflection = ReflectionEngine(marker)
    data = Splits(train=[builtin(ARM)], val=[builtin(ARM)], test=[])
    with dspy.context(adapter=CHAT):
        optimize(_settings("gepa", max_metric_calls=6), out=tmp_path / "p.json", log=tmp_path / "log", lm=lm,
                 reflection_lm=engine_lm(reflection), data=data, say=lambda _: None)
    assert any(marker in s for s in engine.systems)
    shown = "\n".join(reflection.shown)  # GEPA improves the Analyzer first: its feedback says the fault is elsewhere
    assert "Nothing points at the Analyzer's output" in shown and "point at the Planner" in shown


def test_a_gepa_run_resumes_with_a_larger_budget_and_refuses_other_changes(tmp_path: Path) -> None:
    from robotool.optimize.run import OptimizeError

    lm, _ = _task_lm(arm_code=STAND_STILL)
    reflection = ReflectionEngine("GEPA-PROPOSED: move the gripper to the milk before closing it.")
    data = Splits(train=[builtin(ARM)], val=[builtin(ARM)], test=[])
    said: list[str] = []

    def run(**budget: int) -> None:
        optimize(_settings("gepa", **budget), out=tmp_path / "p.json", log=tmp_path / "log", lm=lm,
                 reflection_lm=engine_lm(reflection), data=data, say=said.append)

    with dspy.context(adapter=CHAT):
        run(max_metric_calls=4)
        first = len(reflection.shown)
        run(max_metric_calls=8)
        with pytest.raises(OptimizeError, match="holds a run with other settings"):
            run(max_metric_calls=6)  # a smaller budget is another run
    assert any("resuming the GEPA run" in line and "4 -> 8 metric calls" in line for line in said)
    assert len(reflection.shown) > first  # the extended run reflected further


# -- offline compilation and compiled programs everywhere -------------------------------------------


def test_planner_demos_offline_then_run_eval_and_load(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from robotool.cli import main as robotool_main
    from robotool.cli.eval_command import main as eval_main
    from robotool.cli.optimize_command import main as optimize_main

    out = tmp_path / "p.json"
    assert optimize_main(["--optimizer", "planner-demos", "--families", "milk_reaching", "--train", "1",
                          "--val", "0", "--worlds", "2", "--out", str(out)]) == 0
    stored = json.loads(out.read_text())
    sources = stored["robotool"]["demonstrations"]
    assert len(sources) == 1 and all(len(stored[p]["demos"]) == 1 for p in ("analyze", "plan", "calculate", "code"))
    for source in sources:  # every stored demonstration's code passes `robotool run` on its own instance
        instance = tasks.generate(source["family"], source["seed"])
        task_file = tasks.write_instance(instance, tmp_path / f"{source['task']}.yaml")
        code_file = tmp_path / f"{source['task']}.py"
        code_file.write_text(source["code"])
        assert robotool_main(["run", str(task_file), str(code_file)]) == 0
    assert stored["code"]["demos"][0]["code"] == sources[0]["code"]

    program = RoboTool.from_compiled(out)
    assert program.compiled.optimizer == "planner-demos" and len(program.plan.demos) == 1

    with StandinServer(Script(rules=_standin_rules(GRASP_DIRECTLY))) as server:
        status = eval_main(["--program", str(out), "--tasks", ARM, "--lm", "openai/standin", "--api-base",
                            server.base_url, "--no-cache", "--worlds", "1", "--no-pictures",
                            "--out", str(tmp_path / "eval")])
        coder_prompts = [json.dumps(r["messages"]) for r in server.requests if "[[ ## code ## ]]" in
                         r["messages"][-1]["content"]]
    assert status == 0
    results = json.loads((tmp_path / "eval" / "results.json").read_text())
    assert [r["key"]["method"] for r in results["records"]] == ["p"] and results["records"][0]["success_rate"] == 1.0
    assert any("get_graspable_point('hammer')" in p for p in coder_prompts)  # the demonstration reached the model

    # the file records its training instance; eval refuses to score the program on it without --allow-train
    assert stored["robotool"]["train"] == [f"{sources[0]['family']}#{sources[0]['seed']}"]
    assert stored["robotool"]["val"] == [] and any("Repair stage is left" in n for n in stored["robotool"]["notes"])
    on_train = ["--program", str(out), "--families", sources[0]["family"], "--seeds", str(sources[0]["seed"]),
                "--lm", "openai/standin", "--no-cache", "--worlds", "1", "--no-pictures"]
    with StandinServer(Script(rules=_standin_rules(GRASP_DIRECTLY))) as server:
        refused = eval_main([*on_train, "--api-base", server.base_url, "--out", str(tmp_path / "train")])
        assert refused == 2 and not server.requests
        allowed = eval_main([*on_train, "--api-base", server.base_url, "--out", str(tmp_path / "train"),
                             "--allow-train"])
    err = capsys.readouterr().err
    assert "was trained on milk_reaching#" in err and "--allow-train" in err
    assert allowed in (0, 1)
    report = (tmp_path / "train" / "report.md").read_text()
    assert "p was trained on milk_reaching\\#" in report and "not held out" in report  # Markdown-escaped


def test_a_compiled_program_that_lacks_a_stage_is_refused_clearly(tmp_path: Path) -> None:
    from robotool.program.compiled import CompiledInfo, save_compiled

    path = tmp_path / "coder.json"
    save_compiled(Proposer.method("coder"), path, CompiledInfo(optimizer="bootstrap", method="coder",
                                                              robotool_version="0.0.1"))
    with pytest.raises(CompiledProgramError, match=r"compiled for method coder\) has no stage analyze, plan"):
        RoboTool().load(path)
    loaded = RoboTool.from_compiled(path)
    assert loaded.method_name == "coder" and "compiled with robotool 0.0.1" in loaded.compiled_notes[0]


def test_solve_with_a_compiled_program_over_http(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    from robotool.cli import main as robotool_main
    from robotool.program.compiled import CompiledInfo, save_compiled

    program = Proposer()
    program.code.signature = program.code.signature.with_instructions("COMPILED-CODER-INSTRUCTION")
    save_compiled(program, tmp_path / "p.json", CompiledInfo(optimizer="gepa", method="robotool"))
    with StandinServer(Script(rules=_standin_rules(GRASP_DIRECTLY))) as server:
        status = robotool_main(["solve", ARM, "--program", str(tmp_path / "p.json"), "--lm", "openai/standin",
                                "--api-base", server.base_url, "--no-cache", "--worlds", "1"])
        systems = [m["content"] for r in server.requests for m in r["messages"] if m["role"] == "system"]
    assert status == 0 and any("COMPILED-CODER-INSTRUCTION" in s for s in systems)
    capsys.readouterr()
    assert robotool_main(["solve", ARM, "--program", str(tmp_path / "missing.json"), "--lm", "openai/x"]) == 2
    assert "compiled program not found" in capsys.readouterr().err
    monkeypatch.delenv("ROBOTOOL_LM", raising=False)
    assert robotool_main(["solve", ARM, "--program", str(tmp_path / "p.json")]) == 2
    assert "--program runs its stages on a language model" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--optimizer", "gepa"], "gepa runs the stages on a language model: pass --lm MODEL"),
        (["--optimizer", "planner-demos", "--families", "nonsense"], "unknown task family nonsense"),
        (["--optimizer", "gepa", "--lm", "openai/x", "--auto", "light", "--max-metric-calls", "5"],
         "--auto and --max-metric-calls are two budgets"),
    ],
)
def test_optimize_command_mistakes_end_in_one_line(argv: list[str], message: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    from robotool.cli import main as robotool_main

    assert robotool_main(["optimize", *argv, "--out", str(tmp_path / "p.json"), "--val", "0"]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_log_folder_with_other_settings_is_refused(tmp_path: Path) -> None:
    from robotool.optimize import OptimizeError

    data = Splits(train=[builtin(ARM)], val=[], test=[])
    lm, _ = _task_lm()
    with dspy.context(adapter=CHAT):
        optimize(_settings("bootstrap"), out=tmp_path / "p.json", log=tmp_path / "log", lm=lm, data=data,
                 say=lambda _: None)
        with pytest.raises(OptimizeError, match="other settings \\(worlds\\)"):
            optimize(_settings("bootstrap").model_copy(update={"worlds": 2}), out=tmp_path / "p.json",
                     log=tmp_path / "log", lm=lm, data=data, say=lambda _: None)
