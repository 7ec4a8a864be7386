"""The plan's labels (found by an adversarial run): a program that stacked 400 labels on one spot (200 refused
pushes) cost the host 50 s of CPU to draw, since every place tried for every label was measured anew."""

from __future__ import annotations

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Annotation

from robotool.render import top_view


def _labels(n: int) -> tuple[FigureCanvasAgg, Figure]:
    fig = Figure(figsize=(6, 4), dpi=80)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for k in range(n):
        ax.annotate(f"{k}. refused: cannot push sofa", (0.5, 0.5), xytext=(0, 0), textcoords="offset points")
    canvas.draw()
    return canvas, fig


def test_each_label_is_measured_once_and_none_overlap(monkeypatch: pytest.MonkeyPatch) -> None:
    canvas, fig = _labels(60)
    measured = []
    original = Annotation.get_window_extent

    def counted(self: Annotation, renderer: object = None) -> object:
        measured.append(self)
        return original(self, renderer)

    monkeypatch.setattr(Annotation, "get_window_extent", counted)
    top_view._declutter(canvas, fig.axes[0])
    assert len(measured) == 60
    monkeypatch.setattr(Annotation, "get_window_extent", original)
    renderer = canvas.get_renderer()
    boxes = [t.get_window_extent(renderer) for t in fig.axes[0].texts]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])
