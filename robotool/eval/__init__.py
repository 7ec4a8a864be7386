"""The offline evaluator (`python -m robotool.eval`)."""
