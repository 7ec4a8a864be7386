"""How well the RoboTool program overlaps its LM calls: wall time of K=8 candidates over K=1.

A local OpenAI-compatible stand-in answers every request after a fixed delay (200 ms by default), so
the measurement is the program's concurrency, not a provider's speed. The stand-in's replies are
scripted for this benchmark (a direct grasp on milk_reaching_near, each candidate's program a little
different, so that none is simulated once for several candidates); each solve runs the Analyzer once,
then the Planner, Calculator and Coder per candidate, then verifies K x R worlds in one batch.

    python benchmarks/lm_parallel.py [--delay 0.2] [--worlds 1] [--repeats 3]

It prints the ratio for the whole solve and for its LM phases alone (Analyzer, then the candidates'
stages), since the rest is simulating K programs instead of one.
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

import dspy

from robotool import tasks
from robotool.program.lm import make_lm
from robotool.program.lm_program import RoboTool
from robotool.program.standin import Rule, Script, StandinServer

MAX_CANDIDATES = 8


def _code(k: int) -> str:
    """Candidate ``k``'s program: the same reach, ``k`` mm higher."""
    return (
        f'p = get_graspable_point("milk")\nopen_gripper()\nmove_to_position([p[0], p[1], p[2] + {0.02 + k / 1000:g}])\n'
    )


def _reply(**fields: object) -> str:
    parts = [f"[[ ## {k} ## ]]\n{v if isinstance(v, str) else json.dumps(v)}" for k, v in fields.items()]
    return "\n\n".join([*parts, "[[ ## completed ## ]]"])


SCRIPT = Script(
    note="Benchmark replies (scripted, not a language model).",
    rules=[
        Rule(match="[[ ## analysis ## ]]", reply=_reply(analysis="The milk is in reach.", key_concepts=[])),
        Rule(
            match="[[ ## abstract_plan ## ]]",
            reply=_reply(
                object_roles=[],
                abstract_plan="Reach above the milk.",
                steps=[{"skill": "move_to_position", "objects": ["milk"], "intent": "reach"}],
            ),
        ),
        Rule(match="[[ ## calculation ## ]]", reply=_reply(calculation="Above the grasp point.", parameters=[])),
        *(Rule(match="[[ ## code ## ]]", reply=_reply(code=_code(k)), times=1) for k in range(MAX_CANDIDATES)),
    ],
)


def solve_seconds(script: Script, candidates: int, worlds: int) -> tuple[float, float]:
    """Wall time of one solve with ``candidates`` candidates, against a fresh stand-in, and of its LM calls."""
    program = RoboTool(candidates=candidates, worlds_per_candidate=worlds)
    task = tasks.load("milk_reaching_near")
    with StandinServer(script) as server:
        lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=0)
        started = time.perf_counter()
        with dspy.context(lm=lm):
            solution = program(task=task).solution
        elapsed = time.perf_counter() - started
    assert len(solution.candidates) == candidates and all(c.rollouts for c in solution.candidates)
    assert len({c.code for c in solution.candidates}) == candidates  # every candidate simulated
    return elapsed, solution.timings["analyzer"] + solution.timings["candidates"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--delay", type=float, default=0.2, help="seconds the stand-in waits before answering")
    parser.add_argument("--worlds", type=int, default=1, help="perturbed worlds per candidate")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each K; the best is kept")
    args = parser.parse_args()
    script = SCRIPT.model_copy(update={"delay": args.delay})
    solve_seconds(script, 1, args.worlds)  # warm up the simulator and the sandbox
    k = MAX_CANDIDATES
    runs = {n: [solve_seconds(script, n, args.worlds) for _ in range(args.repeats)] for n in (1, k)}
    total = {n: min(t for t, _ in runs[n]) for n in runs}
    lm = {n: min(t for _, t in runs[n]) for n in runs}
    print(f"stand-in delay {args.delay * 1000:.0f} ms, {args.worlds} world(s) per candidate")
    print(f"solve:     K=1: {total[1]:.2f} s   K={k}: {total[k]:.2f} s   K={k}/K=1: {total[k] / total[1]:.2f}")
    print(f"LM phases: K=1: {lm[1]:.2f} s   K={k}: {lm[k]:.2f} s   K={k}/K=1: {lm[k] / lm[1]:.2f}")


if __name__ == "__main__":
    main()
