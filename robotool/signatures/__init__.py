"""Typed DSPy signatures, one per stage of the RoboTool program (Analyzer, Planner, Calculator, Coder)."""
