"""``report.html``: one self-contained page per evaluation (``python -m robotool.eval``) and per solved or run
task (``robotool solve/run --html FILE``), opened from the file system with no server, no network and no
script: the report's tables and plots, and a drill-down per run (HTML ``<details>``)."""

from robotool.report_page.page import evaluation_page, run_page, solution_page

__all__ = ["evaluation_page", "run_page", "solution_page"]
