"""PNG plots of a summary (matplotlib, Agg backend): success, error breakdown, discriminative tool use, and
repair against plain sampling at equal LM calls."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robotool.eval.metrics import OUTCOMES, Summary
from robotool.eval.solvers import method_label
from robotool.safe_text import plot_text

COLORS = {
    "success": "#4c9a2a",
    "tool_use": "#d1495b",
    "logical": "#edae49",
    "numerical": "#00798c",
    "invalid": "#9e9e9e",
}


def _label(method: str) -> str:
    """A method's name on a plot: a compiled program's is its file's, which the user named (escaped)."""
    return plot_text(method_label(method))


def write_plots(summary: Summary, folder: Path) -> list[str]:
    """Write the plots that have data into ``folder``; returns their file names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written: list[str] = []

    def save(fig: plt.Figure, name: str) -> None:
        for ax in fig.axes:  # legend in a band above the bars
            ax.set_ylim(0, 1.35)
            ncol = min(3, len(ax.get_legend_handles_labels()[0]) or 1)
            ax.legend(fontsize=7, loc="upper center", ncol=ncol, frameon=False)
        fig.tight_layout()
        fig.savefig(folder / name, dpi=120)
        plt.close(fig)
        written.append(name)

    if summary.success or summary.generated:
        by_method: dict[str, dict[str, float]] = {}
        for row in summary.success:
            by_method.setdefault(row.method, {}).update({c: v.value or 0.0 for c, v in row.cells.items()})
        for row in summary.generated:
            by_method.setdefault(row.method, {}).update({f"{c} (gen.)": v.value or 0.0 for c, v in row.cells.items()})
        columns = list(dict.fromkeys(c for values in by_method.values() for c in values))
        fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(columns) + 2), 4))
        width = 0.8 / len(by_method)
        x = np.arange(len(columns))
        for i, (method, values) in enumerate(by_method.items()):
            ax.bar(x + i * width, [values.get(c, 0.0) for c in columns], width, label=_label(method))
        ax.set_xticks(x + 0.4 - width / 2, [plot_text(c) for c in columns], rotation=35, ha="right", fontsize=8)
        ax.set(ylabel="success rate", title="Success by method and task")
        save(fig, "success.png")

    if summary.errors:
        fig, ax = plt.subplots(figsize=(max(5.0, 1.1 * len(summary.errors) + 2), 4))
        labels = [_label(b.method) for b in summary.errors]
        bottom = np.zeros(len(labels))
        for outcome in OUTCOMES:
            shares = np.array([b.shares[outcome] for b in summary.errors])
            ax.bar(labels, shares, bottom=bottom, label=outcome, color=COLORS[outcome])
            bottom += shares
        ax.set(ylabel="share of runs", title="Outcomes and error breakdown")
        ax.tick_params(axis="x", labelrotation=25, labelsize=8)
        save(fig, "errors.png")

    if summary.discrimination:
        fig, ax = plt.subplots(figsize=(max(5.0, 1.1 * len(summary.discrimination) + 2), 4))
        x = np.arange(len(summary.discrimination))
        for offset, (name, attr) in zip(
            (-0.2, 0.2), (("tool needed", "needed"), ("no tool needed", "not_needed")), strict=True
        ):
            ax.bar(x + offset, [getattr(d, attr).value or 0.0 for d in summary.discrimination], 0.4, label=name)
        ax.set_xticks(x, [_label(d.method) for d in summary.discrimination], rotation=25, fontsize=8)
        ax.set(ylabel="tool-use rate", title="Discriminative tool use")
        save(fig, "discrimination.png")

    if summary.repair:
        fig, ax = plt.subplots(figsize=(6, 4))
        for comparison in summary.repair:
            line = ax.plot(
                [comparison.sampled_calls, comparison.plain_calls],
                [comparison.sampled_success, comparison.plain_success],
                "o-",
                label=f"{_label(comparison.method)}: plain best-of-K -> K'",
            )[0]
            ax.plot(
                [comparison.repair_calls],
                [comparison.repair_success],
                "*",
                markersize=12,
                color=line.get_color(),
                label=f"{_label(comparison.method)}: K + repair",
            )
        ax.set(xlabel="LM calls per run", ylabel="success rate", title="Repair against plain sampling")
        save(fig, "repair.png")
    return written
