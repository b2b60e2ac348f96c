"""A self-contained HTML report: headings, text, tables and figures.

Figures are matplotlib figures rendered to PNG once; the PNG is embedded in
the page (base64 data URI, so the file reads offline and can be forwarded
alone) and also kept to be written beside it. Nothing here touches the disk:
:func:`write_report` does, atomically.
"""

from __future__ import annotations

import base64
import html
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

from design.io.results import (  # noqa: E402
    record_outputs, write_atomic, write_atomic_bytes, write_texts)

STYLE = """
body{font-family:system-ui,Segoe UI,Helvetica,Arial,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{border-bottom:2px solid #444;padding-bottom:.2em}h2{margin-top:2em;border-bottom:1px solid #bbb}
table{border-collapse:collapse;margin:.8em 0;font-size:.92em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right}
th{background:#f0f0f0}td.text,th.text{text-align:left}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:.9em;color:#555}
.banner{padding:.8em 1em;font-size:1.15em;font-weight:600;border-radius:4px;margin:1em 0}
.passed{background:#e3f6e3;border:2px solid #2a7a2a}.failed{background:#fde2e2;border:2px solid #b00}
.neutral{background:#eef2f8;border:2px solid #4a6a9a}
nav a{margin-right:1em}code{background:#f4f4f4;padding:0 .2em}
"""


def number(value, digits: int = 4) -> str:
    """A table cell: floats to ``digits`` significant figures, None to '—'."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "—"
        return f"{value:.{digits}g}"
    return str(value)


@dataclass
class Figure:
    """A rendered figure: file name (``*.png``), caption and PNG bytes."""

    name: str
    caption: str
    png: bytes


@dataclass
class Page:
    """An HTML report being assembled, section by section."""

    title: str
    parts: list[str] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    sections: list[tuple[str, str]] = field(default_factory=list)

    def banner(self, text: str, kind: str = "neutral") -> None:
        """A coloured box at the current position; kind: passed, failed or neutral."""
        self.parts.append(f'<div class="banner {kind}" id="verdict">{html.escape(text)}</div>')

    def section(self, title: str, anchor: str) -> None:
        """A level-2 heading, listed in the page's table of contents."""
        self.sections.append((anchor, title))
        self.parts.append(f'<h2 id="{anchor}">{html.escape(title)}</h2>')

    def text(self, text: str) -> None:
        self.parts.append(f"<p>{html.escape(text)}</p>")

    def table(self, rows: list[dict], caption: str = "", table_id: str = "",
              digits: int = 4) -> None:
        """A table of flat dicts (columns from the first row)."""
        if not rows:
            self.text("(no rows)")
            return
        columns = list(rows[0])
        head = "".join(f'<th class="{_align(rows, c)}">{html.escape(str(c))}</th>'
                       for c in columns)
        body = "".join("<tr>" + "".join(
            f'<td class="{_align(rows, c)}">{html.escape(number(r.get(c), digits))}</td>'
            for c in columns) + "</tr>" for r in rows)
        ident = f' id="{table_id}"' if table_id else ""
        cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
        self.parts.append(f"<table{ident}>{cap}<thead><tr>{head}</tr></thead>"
                          f"<tbody>{body}</tbody></table>")

    def fragment(self, html_text: str) -> None:
        """An HTML fragment made elsewhere (an interactive figure), as it is."""
        self.parts.append(html_text)

    def figure(self, fig, name: str, caption: str) -> None:
        """Render a matplotlib figure to PNG, embed it and keep it as ``name``.png."""
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
        plt.close(fig)
        png = buf.getvalue()
        self.figures.append(Figure(f"{name}.png", caption, png))
        data = base64.b64encode(png).decode("ascii")
        self.parts.append(
            f'<figure id="fig-{name}"><img alt="{html.escape(caption)}" '
            f'src="data:image/png;base64,{data}"><figcaption>{html.escape(caption)}'
            f"</figcaption></figure>")

    def render(self) -> str:
        nav = " ".join(f'<a href="#{a}">{html.escape(t)}</a>' for a, t in self.sections)
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{html.escape(self.title)}</title><style>{STYLE}</style></head><body>"
                f"<h1>{html.escape(self.title)}</h1><nav>{nav}</nav>\n"
                + "\n".join(self.parts) + "\n</body></html>\n")


def _align(rows: list[dict], column) -> str:
    numeric = all(isinstance(r.get(column), (int, float)) or r.get(column) is None for r in rows)
    return "" if numeric else "text"


def write_report(out_dir: Path, page: Page, files: dict[str, str] | None = None,
                 name: str = "report.html") -> list[Path]:
    """Write a run's output folder: its rendered ``files`` (name -> text), the
    figures (``figures/*.png``) and then the page, each atomically; then
    remove what an earlier run there wrote and this one did not
    (:func:`~design.io.results.record_outputs`). Returns the paths written."""
    written = write_texts(out_dir, files or {})
    for fig in page.figures:
        path = out_dir / "figures" / fig.name
        write_atomic_bytes(path, fig.png)
        written.append(path)
    write_atomic(out_dir / name, page.render())
    written.append(out_dir / name)
    record_outputs(out_dir, written)
    return written
