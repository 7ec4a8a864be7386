"""Shared test setup: no network, no LM cache, shared models."""

import os

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

import dspy  # noqa: E402 - after the environment is set

dspy.configure_cache(enable_disk_cache=False, enable_memory_cache=False)
