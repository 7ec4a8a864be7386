"""Text drawn over rendered frames: object labels at their projected positions, a title and captions."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib import font_manager
from PIL import Image, ImageDraw, ImageFont

from robotool.safe_text import picture_text

RGB = tuple[int, int, int]
TEXT = (20, 20, 20)
BOX = (255, 255, 255, 215)
CAPTION_BOX = (0, 0, 0, 170)
CAPTION_TEXT = (255, 255, 255)
PAD = 3  # px around text in its box


@dataclass(frozen=True)
class Label:
    """A name drawn next to a point of the picture (pixel column, row), with a swatch of its colour."""

    text: str
    anchor: tuple[float, float]
    colour: RGB


@dataclass(frozen=True)
class CaptionLine:
    """One line of a caption; ``colour`` marks it (refusals red, success green)."""

    text: str
    colour: RGB = CAPTION_TEXT


@functools.cache
def font(size: int, bold: bool = False) -> ImageFont.FreeTypeFont:
    """DejaVu Sans (shipped with matplotlib) at ``size`` px."""
    path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans", weight="bold" if bold else "normal"))
    return ImageFont.truetype(path, size)


def text_size(height: int) -> int:
    """Label font size for a picture ``height`` px high."""
    return max(11, round(height / 36))


def _overlaps(box: tuple[float, float, float, float], placed: Sequence[tuple[float, float, float, float]]) -> bool:
    x0, y0, x1, y1 = box
    return any(x0 < b[2] and b[0] < x1 and y0 < b[3] and b[1] < y1 for b in placed)


def draw_labels(
    image: Image.Image, labels: Sequence[Label], avoid: Sequence[tuple[float, float, float, float]] = ()
) -> None:
    """Draw each label in a box above its anchor (moved up or down to keep labels apart), joined by a line."""
    draw = ImageDraw.Draw(image, "RGBA")
    size = text_size(image.height)
    face = font(size)
    placed = list(avoid)
    step = size + 2 * PAD + 2
    for label in sorted(labels, key=lambda lb: lb.anchor[1]):
        x, y = label.anchor
        text = picture_text(label.text)
        left, top, right, bottom = draw.textbbox((0, 0), text, font=face)
        width, height = right - left + 2 * PAD + size, bottom - top + 2 * PAD
        box = (0.0, 0.0, 0.0, 0.0)
        for k in (1, 2, 3, 4, -1, -2, -3, 5, 6, -4, 7, 8):
            y0 = y - k * step - height / 2 if k > 0 else y - (k + 1) * step + PAD
            x0 = min(max(x - width / 2, 2), image.width - width - 2)
            y0 = min(max(y0, 2), image.height - height - 2)
            box = (x0, y0, x0 + width, y0 + height)
            if not _overlaps(box, placed):
                break
        placed.append(box)
        link_y = box[3] if box[1] < y else box[1]
        draw.line([(x, y), ((box[0] + box[2]) / 2, link_y)], fill=(40, 40, 40, 200), width=1)
        draw.ellipse([x - 2.5, y - 2.5, x + 2.5, y + 2.5], fill=(40, 40, 40, 230))
        draw.rectangle(box, fill=BOX, outline=(90, 90, 90, 200))
        swatch = (box[0] + PAD, box[1] + PAD + 1, box[0] + PAD + size - 4, box[3] - PAD - 1)
        draw.rectangle(swatch, fill=(*label.colour, 255), outline=(60, 60, 60, 255))
        draw.text((box[0] + PAD + size - left, box[1] + PAD - top), text, font=face, fill=TEXT)


def draw_caption(
    image: Image.Image, lines: Sequence[CaptionLine], *, at_top: bool
) -> tuple[float, float, float, float]:
    """Draw ``lines`` in a dark band across the top or bottom of the picture; returns the band's box."""
    if not lines:
        return (0.0, 0.0, 0.0, 0.0)
    draw = ImageDraw.Draw(image, "RGBA")
    size = text_size(image.height)
    face = font(size, bold=True)
    line_height = size + 4
    band = len(lines) * line_height + 2 * PAD + 2
    y0 = 0 if at_top else image.height - band
    draw.rectangle((0, y0, image.width, y0 + band), fill=CAPTION_BOX)
    for i, line in enumerate(lines):
        draw.text(
            (2 * PAD, y0 + PAD + 1 + i * line_height),
            _fit(draw, picture_text(line.text), face, image.width - 4 * PAD),
            font=face,
            fill=line.colour,
        )
    return (0.0, float(y0), float(image.width), float(y0 + band))


def _fit(draw: ImageDraw.ImageDraw, text: str, face: ImageFont.FreeTypeFont, width: int) -> str:
    """``text`` cut with an ellipsis to fit ``width`` px."""
    if draw.textlength(text, font=face) <= width:
        return text
    while text and draw.textlength(text + "…", font=face) > width:
        text = text[:-1]
    return text + "…"


def to_image(pixels: np.ndarray) -> Image.Image:
    """An RGB PIL image of an (H, W, 3) uint8 array."""
    return Image.fromarray(pixels, "RGB")
