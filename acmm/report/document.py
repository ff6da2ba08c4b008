"""The document model (a list of blocks) and its two renderers, Markdown and self-contained HTML.

The page style is package data (``acmm/report/style.css``), read with :mod:`importlib.resources`.
"""
from __future__ import annotations

import base64
import html
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from acmm.report.constants import SECTIONS
from acmm.report.ledger import STATUS_BOUND, STATUS_EXPLAINED, STATUS_MATCHED, STATUS_UNEXPLAINED
from acmm.report.numbers import markdown_table


@dataclass
class Doc:
    """A list of blocks: ("h", level, text, anchor), ("p", text), ("list", items),
    ("table", header, rows, caption), ("fig", stem, caption, files).

    Attributes
    ----------
    blocks : list of tuple
        The blocks, in order.
    """

    blocks: list = field(default_factory=list)

    def h(self, level, text, anchor=""):
        """Add a heading.

        Parameters
        ----------
        level : int
            Heading level (1: a section).
        text : str
            Heading text.
        anchor : str, optional
            HTML anchor (the section key).
        """
        self.blocks.append(("h", level, text, anchor))

    def p(self, text):
        """Add a paragraph.

        Parameters
        ----------
        text : str
            Its text.
        """
        self.blocks.append(("p", text))

    def ul(self, items):
        """Add a bullet list.

        Parameters
        ----------
        items : iterable of str
            The items.
        """
        self.blocks.append(("list", list(items)))

    def table(self, header, rows, caption=""):
        """Add a table (cells turned into str).

        Parameters
        ----------
        header : list of str
            Column titles.
        rows : list of list
            Rows of cells.
        caption : str, optional
            Table caption.
        """
        self.blocks.append(("table", list(header), [[str(c) for c in r] for r in rows], caption))

    def fig(self, stem, caption, files):
        """Add a figure.

        Parameters
        ----------
        stem : str
            File name of the figure under ``figures/``, without suffix.
        caption : str
            Figure caption.
        files : dict
            ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
        """
        self.blocks.append(("fig", stem, caption, files))


def _md_cell(s: str) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def render_markdown(doc: Doc, title: str) -> str:
    """The document as Markdown (figures linked under ``figures/``).

    Parameters
    ----------
    doc : Doc
        The document.
    title : str
        Page title.

    Returns
    -------
    str
        Markdown text.
    """
    out = [f"# {title}", ""]
    for b in doc.blocks:
        if b[0] == "h":
            out += [f"{'#' * (b[1] + 1)} {b[2]}", ""]
        elif b[0] == "p":
            out += [b[1], ""]
        elif b[0] == "list":
            out += [f"- {x}" for x in b[1]] + [""]
        elif b[0] == "table":
            _, header, rows, caption = b
            if caption:
                out += [f"*{caption}*", ""]
            out += markdown_table([_md_cell(c) for c in header], [[_md_cell(c) for c in r] for r in rows]).split("\n")
        elif b[0] == "fig":
            _, stem, caption, files = b
            out += [f"![{caption}](figures/{stem}.png)", "",
                    f"*{caption}* ([PDF](figures/{stem}.pdf))", ""]
    return "\n".join(out)


def _status_class(text: str) -> str:
    if text.startswith((STATUS_MATCHED, STATUS_BOUND, "✔")):
        return "ok"
    if text.startswith(STATUS_UNEXPLAINED):
        return "bad"
    if text.startswith(STATUS_EXPLAINED):
        return "explained"
    return ""


def render_html(doc: Doc, title: str, figdir: Path) -> str:
    """The document as one self-contained HTML page (style sheet and PNGs embedded).

    Parameters
    ----------
    doc : Doc
        The document.
    title : str
        Page title.
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    str
        HTML text.
    """
    e = html.escape
    css = resources.files("acmm.report").joinpath("style.css").read_text(encoding="utf-8")
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>{e(title)}</title>", '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<style>{css}</style></head><body>", f"<h1>{e(title)}</h1>",
             "<nav><strong>Contents</strong><ul>"]
    parts += [f'<li><a href="#{a}">{e(t)}</a></li>' for a, t in SECTIONS]
    parts.append("</ul></nav>")
    for b in doc.blocks:
        if b[0] == "h":
            anchor = f' id="{e(b[3])}"' if b[3] else ""
            parts.append(f"<h{b[1] + 1}{anchor}>{e(b[2])}</h{b[1] + 1}>")
        elif b[0] == "p":
            parts.append(f"<p>{e(b[1])}</p>")
        elif b[0] == "list":
            parts.append("<ul>" + "".join(f"<li>{e(x)}</li>" for x in b[1]) + "</ul>")
        elif b[0] == "table":
            _, header, rows, caption = b
            t = ["<table>"]
            if caption:
                t.append(f"<caption>{e(caption)}</caption>")
            t.append("<thead><tr>" + "".join(f"<th>{e(c)}</th>" for c in header) + "</tr></thead><tbody>")
            for r in rows:
                t.append("<tr>" + "".join(f'<td class="{cls}">{e(c)}</td>' if (cls := _status_class(c)) else
                                          f"<td>{e(c)}</td>" for c in r) + "</tr>")
            t.append("</tbody></table>")
            parts.append("".join(t))
        elif b[0] == "fig":
            _, stem, caption, files = b
            data = base64.b64encode(Path(files["png"]).read_bytes()).decode("ascii")
            parts.append(f'<figure><img alt="{e(caption)}" src="data:image/png;base64,{data}">'
                         f'<figcaption>{e(caption)} (<a href="figures/{e(stem)}.pdf">vector PDF</a>, '
                         f'<a href="figures/{e(stem)}.png">PNG</a>)</figcaption></figure>')
    parts.append("</body></html>")
    return "\n".join(parts)
