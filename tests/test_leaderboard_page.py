"""The leaderboard's page model (:mod:`leaderboard.page`) and its two renderers: each block as
Markdown and as HTML, hostile data escaped in both, and both pages in the same order."""

from __future__ import annotations

import re

import pytest

from leaderboard.page import BulletList, DefinitionList, Figure, Heading, Page, Paragraph, Section, Table
from leaderboard.page_html import html_block, html_inline, to_html
from leaderboard.page_markdown import markdown_block, markdown_text, section_markdown, to_markdown

HOSTILE = "<script>alert(1)</script> | `tick` _x_ [a](b)\nnext & co"
"""A label that would run, link, emphasise, make code, split a cell and break a line if carried unescaped."""


@pytest.mark.parametrize(
    ("block", "markdown", "html"),
    [
        (Heading("Learning curves"), "### Learning curves", "<h3>Learning curves</h3>"),
        (Heading("Optimality gap", 4), "#### Optimality gap", "<h4>Optimality gap</h4>"),
        (
            Paragraph("Run `empathy-zoo watch` & see."),
            "Run `empathy-zoo watch` & see.",
            "<p>Run <code>empathy-zoo watch</code> &amp; see.</p>",
        ),
        (Paragraph("A legend.", note=True), "A legend.", '<p class="note">A legend.</p>'),
        (
            Table(["Method", "Seeds", "harms"], [["DQN", "5", "0.10 [0.00, 0.20]"]]),
            "| Method | Seeds | harms |\n|:---|---:|---:|\n| DQN | 5 | 0.10 [0.00, 0.20] |",
            "<table>\n<thead><tr><th>Method</th><th>Seeds</th><th>harms</th></tr></thead>\n<tbody>\n"
            "<tr><td>DQN</td><td>5</td><td>0.10 [0.00, 0.20]</td></tr>\n</tbody>\n</table>",
        ),
        (
            Table(["Scenario", "Why"], [["cat", "a <fast> cat"]], left_columns=2),
            "| Scenario | Why |\n|:---|:---|\n| cat | a \\<fast\\> cat |",
            "<table>\n<thead><tr><th>Scenario</th><th>Why</th></tr></thead>\n<tbody>\n"
            "<tr><td>cat</td><td>a &lt;fast&gt; cat</td></tr>\n</tbody>\n</table>",
        ),
        (
            Figure("an episode", "figures/x_episode.gif"),
            "![an episode](figures/x_episode.gif)",
            '<img alt="an episode" src="figures/x_episode.gif">',
        ),
        (BulletList(["`a`: 3 runs", "b"]), "- `a`: 3 runs\n- b", "<ul>\n<li><code>a</code>: 3 runs</li>\n<li>b</li>\n</ul>"),
        (
            DefinitionList([("harms", "cats harmed"), ("survival", "steps alive")]),
            "- **harms**: cats harmed\n- **survival**: steps alive",
            "<dl>\n<dt>harms</dt><dd>cats harmed</dd>\n<dt>survival</dt><dd>steps alive</dd>\n</dl>",
        ),
    ],
)
def test_each_block_renders_in_both_formats(block, markdown: str, html: str) -> None:
    assert markdown_block(block) == markdown
    assert html_block(block) == html


def test_an_embedded_figure_is_a_data_uri_and_its_markdown_a_link() -> None:
    figure = Figure("env: harms vs training steps", "figures/env_harms.png", b"not a png")
    assert markdown_block(figure) == "![env: harms vs training steps](figures/env_harms.png)"
    assert html_block(figure) == '<img alt="env: harms vs training steps" src="data:image/png;base64,bm90IGEgcG5n">'


def test_hostile_labels_stay_escaped_in_both_formats() -> None:
    label = markdown_text(HOSTILE)
    page = Page(
        "board",
        [
            Section(
                label,
                [
                    Heading(label, 4),
                    Paragraph(f"Not compared with DQN: {label}.", note=True),
                    Table(["Method", "Against", "harms"], [[HOSTILE, HOSTILE, "1 | 2"]], text_columns=2),
                    Figure(f'{HOSTILE} "quoted"', "figures/x.gif"),
                    BulletList([label]),
                    DefinitionList([(label, label)]),
                ],
            )
        ],
    )
    markdown, html = to_markdown(page), to_html(page)
    image = next(line for line in markdown.splitlines() if line.startswith("!["))
    assert image == '![<script>alert(1)</script> | `tick` _x_ \\[a\\](b) next & co "quoted"](figures/x.gif)'  # (alt text: plain)
    assert "<script>" not in markdown.replace(image, "") and "<script>" not in html
    assert "\\<script\\>" in markdown and "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    table = [line for line in markdown.splitlines() if line.startswith("| ")][1]
    assert table.count(" | ") == 2 and "1 \\| 2" in table  # (three cells: no | of the data splits one)
    assert "\\`tick\\`" in markdown and "<code>" not in html  # (a label's backticks make no code span)
    assert "\\_x\\_" in markdown and "\\[a\\](b)" in markdown
    assert "\nnext" not in markdown  # (a label stays on its line; in HTML a line break is a space)
    # the HTML shows the label as itself: Markdown's escapes resolved, then escaped for HTML
    assert "&lt;script&gt;alert(1)&lt;/script&gt; | `tick` _x_ [a](b) next &amp; co" in html
    assert 'alt="&lt;script&gt;alert(1)&lt;/script&gt; | `tick` _x_ [a](b)\nnext &amp; co &quot;quoted&quot;"' in html
    assert "![\\<script>" not in markdown and '\\[a\\](b) next & co "quoted"](figures/x.gif)' in markdown


def test_markdown_escapes_resolve_to_the_text_in_html() -> None:
    for text in (HOSTILE.replace("\n", " "), "a\\b", "x_", "_y", "*bold*", "C:\\dir\\`"):
        assert html_inline(markdown_text(text)) == html_inline_plain(text)


def html_inline_plain(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def test_both_formats_carry_the_same_sections_in_the_same_order() -> None:
    sections = [
        Section("", [Paragraph("Produced by `cmd`.")]),
        Section("coexistence\\_v0 \\<b\\>", [Heading("Final greedy evaluation"), Table(["Method"], [["DQN"]])]),
        Section("", [Paragraph("† a single seed.", note=True)]),
        Section("Held-out partners", [Heading("scenario set", 3), Heading("harms", 4)]),
        Section("Empty"),
        Section("Metric definitions", [DefinitionList([("harms", "cats harmed")])]),
    ]
    page = Page("empathy-zoo leaderboard", sections)
    markdown, html = to_markdown(page), to_html(page)
    md_headings = re.findall(r"^(#+) (.*)$", markdown, flags=re.M)
    html_headings = re.findall(r"<h(\d)>(.*?)</h\1>", html)
    assert [(len(hashes), html_inline(text)) for hashes, text in md_headings] == [(int(n), text) for n, text in html_headings]
    assert [text for _, text in html_headings] == [
        "empathy-zoo leaderboard",
        "coexistence_v0 &lt;b&gt;",
        "Final greedy evaluation",
        "Held-out partners",
        "scenario set",
        "harms",
        "Empty",
        "Metric definitions",
    ]
    assert markdown.index("Produced by") < markdown.index("† a single") < markdown.index("## Held-out")
    assert html.index("Produced by") < html.index("† a single") < html.index("<h2>Held-out")
    assert markdown.endswith("- **harms**: cats harmed\n") and "\n\n\n" not in markdown
    assert html.endswith("</dl>\n</body>\n</html>\n")
    assert section_markdown(sections[3]) == "## Held-out partners\n\n### scenario set\n\n#### harms"
    assert section_markdown(Section()) == ""
