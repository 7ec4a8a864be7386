"""The language-model path: the four stages that propose programs, and the verified best-of-K with repair.

:mod:`~robotool.program.lm` (model configuration and what its failures mean), :mod:`~robotool.program.lm_calls`
(one stage's call, parsed leniently and accounted for), :mod:`~robotool.program.lm_program` (``Proposer``, the
optimisable stages, and ``RoboTool``, which also verifies), :mod:`~robotool.program.methods` (the paper's ablations),
:mod:`~robotool.program.repair_rounds`, :mod:`~robotool.program.compiled` (optimised-program files) and
:mod:`~robotool.program.standin` (a scripted stand-in for an LM server). Imported by module; nothing is loaded here,
so ``import robotool.program.methods`` does not load DSPy.
"""
