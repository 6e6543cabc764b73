"""The report as one HTML page: a small Markdown-to-HTML converter for the report's subset.

The report's Markdown (``index.md``) uses headings, paragraphs, bullet and
numbered lists, GitHub-style tables, images, links, code blocks and inline
bold, italic and code.  :func:`markdown_to_html` converts exactly that subset
(no dependency: the ``markdown`` package would do it too, but this is 150
lines, fully tested and needs no install step).  Anything else is kept as
escaped text, so nothing is lost or interpreted as HTML.  Underscores are
not emphasis (the report writes symbols such as ``p_m`` and ``F_max``).

:func:`report_page` wraps the converted body in a page with a navigation
bar listing the sections (``##`` headings) and a little CSS; the report
builder writes it as ``index.html`` next to ``index.md``.
"""

from __future__ import annotations

import html
import re

_IMG = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)")
_LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)")
_CODE = re.compile(r"`([^`]+)`")
_BOLD = re.compile(r"\*\*(?=\S)(.+?)(?<=\S)\*\*")
_ITAL = re.compile(r"(?<![*\w])\*(?=\S)(.+?)(?<=\S)\*(?![*\w])")
_HEAD = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_ULI = re.compile(r"^(\s*)[*-]\s+(.*)$")
_OLI = re.compile(r"^(\s*)\d+[.)]\s+(.*)$")
_TABLE_SEP = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def slug(text: str, used: set | None = None) -> str:
    """An HTML id for a heading: lower case, words joined by ``-``, unique within ``used``.

    Parameters
    ----------
    text : str
        Heading text (Markdown).
    used : set of str, optional
        Ids already taken; the new id is added to it.
    """
    s = re.sub(r"[^\w]+", "-", re.sub(r"[`*]", "", text).lower(), flags=re.UNICODE).strip("-")
    s = s or "section"
    if used is not None:
        base, n = s, 2
        while s in used:
            s, n = f"{base}-{n}", n + 1
        used.add(s)
    return s


def inline(text: str) -> str:
    """Inline Markdown (images, links, code, bold, italic) to HTML; the rest is escaped.

    Parameters
    ----------
    text : str
        One line or paragraph of Markdown.
    """
    slots: list[str] = []

    def keep(s: str) -> str:
        slots.append(s)
        return f"\x00{len(slots) - 1}\x00"

    t = _CODE.sub(lambda m: keep(f"<code>{html.escape(m.group(1))}</code>"), text)
    t = _IMG.sub(lambda m: keep(f'<img src="{html.escape(m.group(2), quote=True)}" alt="'
                                f'{html.escape(m.group(1), quote=True)}" loading="eager">'), t)
    t = _LINK.sub(lambda m: keep(f'<a href="{html.escape(m.group(2), quote=True)}">'
                                 f"{html.escape(m.group(1))}</a>"), t)
    t = html.escape(t, quote=False)
    t = _BOLD.sub(r"<strong>\1</strong>", t)
    t = _ITAL.sub(r"<em>\1</em>", t)
    return re.sub("\x00(\\d+)\x00", lambda m: slots[int(m.group(1))], t)


def _cells(line: str) -> list[str]:
    s = line.strip()
    if s.startswith("|"):
        s = s[1:]
    if s.endswith("|") and not s.endswith("\\|"):
        s = s[:-1]
    return [c.strip() for c in re.split(r"(?<!\\)\|", s)]


def _table(lines: list[str]) -> str:
    head = _cells(lines[0])
    out = ["<table>", "<thead><tr>" + "".join(f"<th>{inline(c)}</th>" for c in head)
           + "</tr></thead>", "<tbody>"]
    for ln in lines[2:]:
        cells = _cells(ln)
        cells += [""] * (len(head) - len(cells))
        out.append("<tr>" + "".join(f"<td>{inline(c)}</td>" for c in cells[:len(head)]) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def markdown_to_html(md: str) -> tuple[str, list]:
    """Convert the report's Markdown subset to an HTML fragment.

    Parameters
    ----------
    md : str
        Markdown text.

    Returns
    -------
    html : str
        The HTML body fragment.
    toc : list of (int, str, str)
        (level, id, text) of every heading, for the navigation.
    """
    lines = md.replace("\r\n", "\n").split("\n")
    out, toc, used = [], [], set()
    para: list[str] = []
    i = 0

    def flush():
        if para:
            out.append(f"<p>{inline(' '.join(s.strip() for s in para))}</p>")
            para.clear()

    while i < len(lines):
        ln = lines[i]
        if not ln.strip():
            flush()
            i += 1
            continue
        if ln.lstrip().startswith("```"):
            flush()
            j = i + 1
            while j < len(lines) and not lines[j].lstrip().startswith("```"):
                j += 1
            out.append("<pre><code>" + html.escape("\n".join(lines[i + 1:j])) + "</code></pre>")
            i = j + 1
            continue
        m = _HEAD.match(ln)
        if m:
            flush()
            level, text = len(m.group(1)), m.group(2)
            hid = slug(text, used)
            toc.append((level, hid, text))
            out.append(f'<h{level} id="{hid}">{inline(text)}</h{level}>')
            i += 1
            continue
        if "|" in ln and i + 1 < len(lines) and _TABLE_SEP.match(lines[i + 1]):
            flush()
            j = i + 2
            while j < len(lines) and lines[j].strip() and "|" in lines[j]:
                j += 1
            out.append(_table(lines[i:j]))
            i = j
            continue
        lm = _ULI.match(ln) or _OLI.match(ln)
        if lm and not para:
            tag = "ul" if _ULI.match(ln) else "ol"
            items = []
            j = i
            while j < len(lines) and lines[j].strip():
                mm = _ULI.match(lines[j]) if tag == "ul" else _OLI.match(lines[j])
                if mm:
                    items.append(mm.group(2))
                elif items:
                    items[-1] += " " + lines[j].strip()      # continuation line
                j += 1
            out.append(f"<{tag}>" + "".join(f"<li>{inline(t)}</li>" for t in items) + f"</{tag}>")
            i = j
            continue
        para.append(ln)
        i += 1
    flush()
    return "\n".join(out), toc


_CSS = """
body{font-family:system-ui,sans-serif;margin:0;display:flex;color:#222;line-height:1.45}
nav{position:sticky;top:0;align-self:flex-start;height:100vh;overflow:auto;width:16rem;
 flex:none;background:#f4f4f6;border-right:1px solid #ddd;padding:1rem;box-sizing:border-box}
nav a{display:block;color:#225;text-decoration:none;margin:.3rem 0;font-size:.9rem}
nav a.h3{margin-left:1rem;font-size:.82rem}
main{padding:1rem 2rem;max-width:70rem;min-width:0}
img{max-width:100%;height:auto;display:block;margin:.5rem 0}
table{border-collapse:collapse;margin:.6rem 0;font-size:.85rem;display:block;overflow-x:auto}
th,td{border:1px solid #ccc;padding:.2rem .45rem;text-align:right;white-space:nowrap}
th{background:#eef}
td:first-child,th:first-child{text-align:left}
code{background:#f2f2f2;padding:0 .2rem}
"""


def report_page(md: str, *, title: str = "ppamsafety report") -> str:
    """A complete HTML page for a report's Markdown, with section navigation.

    Parameters
    ----------
    md : str
        The report's Markdown (``index.md``).
    title : str
        Page title.

    Returns
    -------
    str
        The HTML document (UTF-8; images and links stay relative, so the page
        works next to the report's files).
    """
    body, toc = markdown_to_html(md)
    nav = "\n".join(f'<a class="h{lv}" href="#{hid}">{inline(t)}</a>'
                    for lv, hid, t in toc if lv in (2, 3))
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f"<title>{html.escape(title)}</title>\n<style>{_CSS}</style>\n</head>\n<body>\n"
            f'<nav aria-label="sections"><strong>Sections</strong>\n{nav}\n</nav>\n'
            f"<main>\n{body}\n</main>\n</body>\n</html>\n")


__all__ = ["markdown_to_html", "report_page", "inline", "slug"]
