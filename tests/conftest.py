"""Shared test setup: no network, no LM cache, shared models."""

import os

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
