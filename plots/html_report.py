"""report.html: the report as one self-contained page, readable offline.

It is report.md rendered (the one text of the report: the two can never disagree), with each
chart's PNG inlined as base64 and a small hand-written script (no library, no CDN) that makes
every table sortable (click a header) and filterable (one drop-down per column naming a model,
query, path, method or status, and a free-text box). Only the Markdown the report writes is
understood: headings, paragraphs, bullet lists, tables, images, links, **bold**, _italic_ and
`code`. Standard library only.
"""
import base64
import html
import os
import re

# Columns offered as drop-down filters: a model, a query, a query path, a method, a status.
FILTER_COLUMNS = re.compile(r"^(model|mesh|query|path|method|peer|status|fastest exact|host|"
                            r"ebp-octree.*)$", re.IGNORECASE)

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 1.5em auto;
       max-width: 1500px; padding: 0 1em; color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; border-bottom: 1px solid #ddd; margin-top: 1.8em; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0 1em; }
th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: left; vertical-align: top; }
th { background: #f0f0f0; cursor: pointer; user-select: none; position: sticky; top: 0; }
th.sorted-asc::after { content: " \\25B2"; } th.sorted-desc::after { content: " \\25BC"; }
tr:nth-child(even) td { background: #fafafa; }
td.n { white-space: nowrap; }
img.chart { max-width: 100%; height: auto; border: 1px solid #eee; }
code { background: #f4f4f4; padding: 0 3px; font-size: 0.92em; }
.filters { font-size: 0.85em; margin: 0.3em 0; }
.filters select, .filters input { margin-right: 0.6em; font-size: 0.95em; }
.count { color: #666; font-size: 0.85em; }
li.warn, p.warn { color: #a00; }
nav { font-size: 0.85em; background: #f7f7f7; padding: 0.4em 0.8em; }
nav a { margin-right: 0.9em; }
"""

SCRIPT = r"""
(function () {
  "use strict";
  function cellValue(td) {
    var t = td.textContent.trim();
    var m = t.match(/^[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?/);
    if (!m || t === "") return { num: null, text: t.toLowerCase() };
    var v = parseFloat(m[0]);
    var rest = t.slice(m[0].length).trim();
    var scale = { "k": 1e3, "M": 1e6, "G": 1e9, "T": 1e12, "m": 1e-3, "\u00b5": 1e-6, "n": 1e-9 };
    var p = rest.charAt(0);
    if (scale[p] !== undefined && rest.length > 1) v *= scale[p];
    else if (scale[p] !== undefined && rest.length === 1) v *= scale[p];
    return { num: v, text: t.toLowerCase() };
  }
  function compare(a, b) {
    if (a.num !== null && b.num !== null) return a.num - b.num;
    if (a.num !== null) return -1;
    if (b.num !== null) return 1;
    return a.text < b.text ? -1 : a.text > b.text ? 1 : 0;
  }
  function setup(table, index) {
    var head = table.tHead.rows[0];
    var body = table.tBodies[0];
    var rows = Array.prototype.slice.call(body.rows);
    var filters = document.createElement("div");
    filters.className = "filters";
    var selects = [];
    var filterCols = (table.getAttribute("data-filter-columns") || "").split(",")
      .filter(function (s) { return s !== ""; }).map(Number);
    filterCols.forEach(function (col) {
      var values = {};
      rows.forEach(function (r) { if (r.cells[col]) values[r.cells[col].textContent.trim()] = 1; });
      var sel = document.createElement("select");
      sel.setAttribute("data-column", col);
      sel.setAttribute("aria-label", head.cells[col].textContent);
      var all = document.createElement("option");
      all.value = ""; all.textContent = head.cells[col].textContent + ": all";
      sel.appendChild(all);
      Object.keys(values).sort().forEach(function (v) {
        var o = document.createElement("option"); o.value = v; o.textContent = v; sel.appendChild(o);
      });
      sel.addEventListener("change", apply);
      selects.push(sel);
      filters.appendChild(sel);
    });
    var box = document.createElement("input");
    box.type = "search"; box.placeholder = "filter rows\u2026";
    box.addEventListener("input", apply);
    filters.appendChild(box);
    var count = document.createElement("span");
    count.className = "count";
    filters.appendChild(count);
    table.parentNode.insertBefore(filters, table);
    function apply() {
      var text = box.value.toLowerCase();
      var shown = 0;
      rows.forEach(function (r) {
        var ok = selects.every(function (s) {
          var c = r.cells[+s.getAttribute("data-column")];
          return s.value === "" || (c && c.textContent.trim() === s.value);
        }) && (text === "" || r.textContent.toLowerCase().indexOf(text) >= 0);
        r.style.display = ok ? "" : "none";
        if (ok) shown++;
      });
      count.textContent = shown + " of " + rows.length + " rows";
    }
    Array.prototype.forEach.call(head.cells, function (th, col) {
      th.title = "sort";
      th.addEventListener("click", function () {
        var asc = !th.classList.contains("sorted-asc");
        Array.prototype.forEach.call(head.cells, function (h) {
          h.classList.remove("sorted-asc", "sorted-desc");
        });
        th.classList.add(asc ? "sorted-asc" : "sorted-desc");
        rows.sort(function (a, b) {
          var d = compare(cellValue(a.cells[col]), cellValue(b.cells[col]));
          return asc ? d : -d;
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
    apply();
    table.setAttribute("data-ready", "1");
  }
  document.querySelectorAll("table.report").forEach(setup);
  document.body.setAttribute("data-tables-ready", String(document.querySelectorAll("table.report").length));
})();
"""


def _inline(text):
    """Inline Markdown (code, images, links, bold, italic) to HTML; text escaped."""
    out, pos = [], 0
    for m in re.finditer(r"`([^`]*)`", text):
        out.append(_inline_plain(text[pos:m.start()]))
        out.append(f"<code>{html.escape(m.group(1))}</code>")
        pos = m.end()
    out.append(_inline_plain(text[pos:]))
    return "".join(out)


def _inline_plain(text):
    t = html.escape(text, quote=False).replace("\\|", "|")
    t = re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)",
               lambda m: f'<a href="{html.escape(m.group(2))}">{m.group(1)}</a>', t)
    t = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", t)
    t = re.sub(r"(?<![\w])_(.+?)_(?![\w])", r"<em>\1</em>", t)
    return t


def _split_row(line):
    """The cells of a Markdown table line '| a | b |' (an escaped \\| stays in its cell)."""
    inner = line.strip()
    inner = inner[1:] if inner.startswith("|") else inner
    inner = inner[:-1] if inner.endswith("|") and not inner.endswith("\\|") else inner
    return [c.strip() for c in re.split(r"(?<!\\)\|", inner)]


def _table(lines):
    header = _split_row(lines[0])
    filt = [i for i, h in enumerate(header) if FILTER_COLUMNS.match(h.strip("*"))]
    out = [f'<table class="report" data-filter-columns="{",".join(map(str, filt))}">',
           "<thead><tr>" + "".join(f"<th>{_inline(h)}</th>" for h in header) + "</tr></thead>",
           "<tbody>"]
    for line in lines[2:]:
        # Short cells (names, rates) on one line, so that a table stays one screen tall.
        tds = [(' class="n"' if len(c) <= 32 else "", _inline(c)) for c in _split_row(line)]
        out.append("<tr>" + "".join(f"<td{cls}>{text}</td>" for cls, text in tds) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def _image(alt, src, folder):
    path = os.path.join(folder, src)
    if src.endswith(".png") and os.path.isfile(path):
        with open(path, "rb") as fh:
            data = base64.b64encode(fh.read()).decode("ascii")
        src_attr = f"data:image/png;base64,{data}"
    else:
        src_attr = html.escape(src)
    return f'<p><img class="chart" alt="{html.escape(alt)}" src="{src_attr}"></p>'


def _anchor(title):
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")


def render(md, folder, title):
    """The HTML page of a report's Markdown `md`, images read from `folder`."""
    body, nav = [], []
    lines = md.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if not line.strip():
            i += 1
            continue
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            text = line[level:].strip()
            anchor = _anchor(text)
            if level == 2:
                nav.append(f'<a href="#{anchor}">{_inline(text)}</a>')
            body.append(f'<h{level} id="{anchor}">{_inline(text)}</h{level}>')
            i += 1
        elif line.startswith("|"):
            block = []
            while i < len(lines) and lines[i].startswith("|"):
                block.append(lines[i])
                i += 1
            body.append(_table(block) if len(block) >= 2 else f"<p>{_inline(block[0])}</p>")
        elif re.match(r"^!\[[^\]]*\]\([^)]+\)\s*$", line):
            m = re.match(r"^!\[([^\]]*)\]\(([^)]+)\)", line)
            body.append(_image(m.group(1), m.group(2), folder))
            i += 1
        elif line.startswith("- "):
            items = []
            while i < len(lines) and lines[i].startswith("- "):
                cls = ' class="warn"' if "\u26a0" in lines[i] else ""
                items.append(f"<li{cls}>{_inline(lines[i][2:])}</li>")
                i += 1
            body.append("<ul>" + "".join(items) + "</ul>")
        else:
            para = []
            while (i < len(lines) and lines[i].strip() and not lines[i].startswith(("#", "|", "- "))
                   and not lines[i].startswith("![")):
                para.append(lines[i].lstrip("> "))
                i += 1
            text = " ".join(para)
            cls = ' class="warn"' if "\u26a0" in text else ""
            body.append(f"<p{cls}>{_inline(text)}</p>")
    if nav:   # the sections' links under the title
        at = next((k + 1 for k, b in enumerate(body) if b.startswith("<h1")), 0)
        body.insert(at, f"<nav>{''.join(nav)}</nav>")
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>\n"
            + "\n".join(body) + f"\n<script>{SCRIPT}</script>\n</body></html>\n")
