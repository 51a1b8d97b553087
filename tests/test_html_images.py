"""The leaderboard's HTML embeds each figure as a smaller palette copy; the figure files stay as drawn."""

from __future__ import annotations

import base64
import io

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from PIL import Image

from leaderboard.html_images import embedded_png, img_tag


def figure_png() -> bytes:
    fig, ax = plt.subplots(figsize=(5, 3), dpi=100)
    for k in range(4):
        ax.plot(range(50), [x * (k + 1) for x in range(50)], label=f"row {k}")
    ax.legend()
    ax.set_title("harms per episode")
    out = io.BytesIO()
    fig.savefig(out, format="png")
    plt.close(fig)
    return out.getvalue()


def test_the_embedded_copy_is_smaller_same_size_and_close_in_colour():
    png = figure_png()
    small = embedded_png(png)
    assert len(small) < len(png) / 2
    with Image.open(io.BytesIO(png)) as original, Image.open(io.BytesIO(small)) as reduced:
        assert original.size == reduced.size
        a = np.asarray(original.convert("RGB"), dtype=int)
        b = np.asarray(reduced.convert("RGB"), dtype=int)
    error = np.abs(a - b).max(axis=2)  # (per pixel, the largest channel error in 0..255)
    assert error.mean() < 2 and np.percentile(error, 99) <= 32  # (antialiased edges move a little)
    assert embedded_png(png) == small  # (the same figure, the same bytes)


def test_the_img_tag_holds_the_copy_and_escapes_its_alt_text():
    png = figure_png()
    tag = img_tag(png, 'a "quoted" <title>')
    assert tag.startswith('<img alt="a &quot;quoted&quot; &lt;title&gt;" src="data:image/png;base64,')
    data = tag.split("base64,", 1)[1].removesuffix('">')
    assert base64.b64decode(data) == embedded_png(png)


def test_bytes_that_are_no_image_are_embedded_as_they_are():
    assert embedded_png(b"not a png") == b"not a png"
