"""The RoboTool program and the paper's ablations, as switches of the same stages."""

STAGES_BY_METHOD: dict[str, dict[str, bool]] = {
    "robotool": {"analyzer": True, "planner": True, "calculator": True},
    "no_analyzer": {"analyzer": False, "planner": True, "calculator": True},
    "no_calculator": {"analyzer": True, "planner": True, "calculator": False},
    "planner_coder": {"analyzer": False, "planner": True, "calculator": False},
    "coder": {"analyzer": False, "planner": False, "calculator": False},
}
"""Method name -> which LM stages run (the Coder always does)."""
