"""The self-contained HTML report: inline CSS, figures as data: URIs, no script, no network."""
from __future__ import annotations

import html
import json

from bsdflab.validation.registry import FAMILIES

CSS = """
body{font:14px/1.45 system-ui,-apple-system,Segoe UI,sans-serif;margin:0;color:#1c1c1c;background:#fafafa}
header{padding:18px 28px;color:#fff}header.ok{background:#2e7d32}header.bad{background:#b71c1c}
header h1{margin:0 0 4px;font-size:22px}header p{margin:2px 0}
nav{padding:8px 28px;background:#eee;border-bottom:1px solid #ddd}nav a{margin-right:14px}
main{padding:8px 28px 40px}h2{margin-top:28px;border-bottom:2px solid #ccc}
table{border-collapse:collapse;width:100%;margin:8px 0}th,td{padding:4px 8px;text-align:left;vertical-align:top}
th{background:#e8e8e8}tr.row td{border-top:1px solid #ddd}
tr.pass td.status{background:#c8e6c9}tr.fail td,tr.error td{background:#ffd6d6}tr.skipped td{color:#777}
tr.study td.status{background:#bbdefb}td.status{font-weight:700;text-transform:uppercase;width:64px}
td.num{font-family:ui-monospace,monospace;white-space:nowrap}
details{margin:2px 0 8px}summary{cursor:pointer;color:#1a4f9c}
pre{background:#f0f0f0;padding:8px;overflow-x:auto;font-size:12px;max-height:320px}
figure{margin:8px 0}figure img{max-width:100%;border:1px solid #ddd;background:#fff}
figcaption{font-size:12px;color:#555}.small{font-size:12px;color:#555}
.kv td:first-child{font-weight:600;width:220px}
"""

STATUS_TEXT = {"pass": "pass", "fail": "FAIL", "error": "ERROR", "skipped": "skip", "study": "study"}


def _e(x) -> str:
    return html.escape(str(x))


def _num(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, str):
        return _e(x)
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def _figures(figures) -> str:
    return "".join(f'<figure><img alt="{_e(f.caption)}" src="data:image/png;base64,{f.png_base64}">'
                   f"<figcaption>{_e(f.caption)}</figcaption></figure>" for f in figures)


def _check_rows(rows, results_by_name) -> str:
    out = ['<table><tr><th>status</th><th>check</th><th>statistic</th><th>measured</th><th>limit</th>'
           '<th>reference</th><th>time</th></tr>']
    for row in rows:
        r = results_by_name[row["name"]]
        tol = row["tolerance"]
        out.append(f'<tr class="row {row["status"]}" id="{_e(row["name"])}"><td class="status">'
                   f'{STATUS_TEXT[row["status"]]}</td><td><b>{_e(row["name"])}</b><br>'
                   f'<span class="small">{_e(row["title"])}</span></td><td>{_e(row["statistic"])}</td>'
                   f'<td class="num">{_num(row["value"])}</td><td class="num">{_e(tol["comparison"])} '
                   f'{_num(tol["limit"])}</td><td>{_e(row["reference"])}</td>'
                   f'<td class="num">{row["duration_s"]:.1f} s</td></tr>')
        opened = " open" if row["status"] in ("fail", "error") else ""
        body = (f'<table class="kv"><tr><td>model</td><td>{_e(row["model"])}</td></tr>'
                f'<tr><td>tolerance and its derivation</td><td>{_e(tol["derivation"])}</td></tr>'
                f'<tr><td>result</td><td>{_e(row["message"]) if row["status"] != "error" else ""}</td></tr>'
                f'<tr><td>seed, effort</td><td>{row["seed"]}, {_e(json.dumps(row["effort"]))}</td></tr></table>')
        if row["status"] == "error":
            body += f"<pre>{_e(row['message'])}</pre>"
        if row["details"]:
            body += (f"<details><summary>numbers</summary><pre>{_e(json.dumps(row['details'], indent=1))}</pre>"
                     f"</details>")
        if row["kind"] != "study":
            body += _figures(r.figures)
        out.append(f'<tr class="{row["status"]}"><td></td><td colspan="6"><details{opened}>'
                   f"<summary>details and figures</summary>{body}</details></td></tr>")
    out.append("</table>")
    return "".join(out)


def _approximations(doc, results_by_name) -> str:
    from bsdflab.reference.approximations.standards import SNAKE_FILM, STANDARDS, can_represent

    studies = [c for c in doc["checks"] if c["kind"] == "study"]
    if not studies:
        return "<p>No approximation study in this run.</p>"
    parts = ["<p>Renderers and material standards model thin-film iridescence with approximations "
             "evaluated in RGB. Each is implemented here from its published specification as a "
             "comparison model (<code>bsdflab.reference.approximations</code>, never a bsdflab material) "
             "and compared with bsdflab's exact spectral film: CIEDE2000 over angle x thickness; "
             "&Delta;E<sub>00</sub> &gt; 2 is a visible difference.</p>"]
    snake = next((c for c in studies if c["name"].endswith("/snake")), None)
    for c in studies:
        parts.append(f'<h3 id="{_e(c["name"])}">{_e(c["title"])}</h3><p class="small">{_e(c["reference"])}</p>')
        if c["status"] == "error":
            parts.append(f"<pre>{_e(c['message'])}</pre>")
            continue
        parts.append("<table><tr><th>map</th><th>model</th><th>fraction &Delta;E00 &gt; 2</th><th>median</th>"
                     "<th>95th percentile</th><th>max</th></tr>")
        for label, models in c["details"].items():
            if not isinstance(models, dict) or label.startswith("grid_cells"):
                continue
            for name, v in models.items():
                parts.append(f"<tr><td>{_e(label)}</td><td>{_e(name)}</td><td class='num'>"
                             f"{100 * v['fraction_over_jnd']:.0f}%</td><td class='num'>{v['median_delta_e00']:.1f}</td>"
                             f"<td class='num'>{v['p95_delta_e00']:.1f}</td>"
                             f"<td class='num'>{v['max_delta_e00']:.1f}</td></tr>")
        parts.append("</table>")
        cells = c["details"].get("grid_cells_median_delta_e00_over_angle")
        if cells:
            names = list(next(iter(cells.values())))
            parts.append("<table><tr><th>grid cell: median &Delta;E00 over angle</th>"
                         + "".join(f"<th>{_e(n)}</th>" for n in names) + "</tr>")
            for cell, v in cells.items():
                parts.append(f"<tr><td>{_e(cell)}</td>"
                             + "".join(f"<td class='num'>{v[n]:.1f}</td>" for n in names) + "</tr>")
            parts.append("</table>")
        parts.append(_figures(results_by_name[c["name"]].figures))
    parts.append(f"<h3>Which standards can represent the snake's film?</h3><p class='small'>guanine n = "
                 f"{SNAKE_FILM['film_ior']}, {SNAKE_FILM['thickness_nm']:g} nm (paper sweep "
                 f"{SNAKE_FILM['thickness_sweep_nm'][0]:g}-{SNAKE_FILM['thickness_sweep_nm'][1]:g} nm) on keratin "
                 f"n = {SNAKE_FILM['base_ior']}. Colour error: that standard's model on the snake map above.</p>")
    parts.append("<table><tr><th>standard</th><th>thickness</th><th>film index</th><th>base index</th>"
                 "<th>represents it</th><th>fraction &Delta;E00 &gt; 2 (snake map)</th></tr>")
    snake_errors = next(iter(snake["details"].values()), {}) if snake and snake["status"] != "error" else {}
    for name, s in STANDARDS.items():
        err = snake_errors.get(s["model"], {}).get("fraction_over_jnd")
        parts.append(f"<tr><td>{_e(name)}</td><td>{_e(s['thickness_note'])}</td><td>{_e(s['film_note'])}</td>"
                     f"<td>{_e(s['base'])}</td><td>{'yes' if can_represent(s) else 'no'}</td>"
                     f"<td class='num'>{'-' if err is None else f'{100 * err:.0f}%'}</td></tr>")
    parts.append("</table>")
    return "".join(parts)


def _performance(doc) -> str:
    if not doc["performance"]:
        return (f"<p>Not run at level <b>{_e(doc['level'])}</b> (benchmarks run at standard and full; "
                "they compare against a peer in the same run and print ratios).</p>")
    m = doc["provenance"]["machine"]
    parts = [f"<p class='small'>machine: {_e(m.get('cpu'))}, {m.get('cores')} cores, load average "
             f"{_e(m.get('load_average_1_5_15'))} when the report started (ratios come from one run, so a "
             "shared machine's load affects both sides alike).</p>"]
    for b in doc["performance"]:
        ratios = "".join(f"<li><code>{_e(line)}</code></li>" for line in b["ratios"]) or "<li>no ratio printed</li>"
        parts.append(f"<h3>{_e(b['name'])} <span class='small'>({b['seconds']} s, exit {b['returncode']})</span></h3>"
                     f"<ul>{ratios}</ul><details><summary>full output</summary><pre>{_e(b['output'])}</pre></details>")
    return "".join(parts)


def _provenance(doc) -> str:
    p = doc["provenance"]
    rows = [("created (UTC)", p["created_utc"]), ("command", p.get("command")), ("level", p["level"]),
            ("git commit", f"{p['git_commit']}{' (uncommitted changes)' if p.get('git_dirty') else ''}"),
            ("Mitsuba variant", p.get("mitsuba_variant")), ("core threads", p.get("core_threads"))]
    rows += [(f"version: {k}", v) for k, v in p["versions"].items()]
    rows += [(f"core build: {k}", v) for k, v in p["core_build"].items()]
    rows += [(f"machine: {k}", v) for k, v in p["machine"].items()]
    return "<table class='kv'>" + "".join(f"<tr><td>{_e(k)}</td><td>{_e(v)}</td></tr>" for k, v in rows) + "</table>"


def _dashboard(doc, sections) -> str:
    """One line per family: counts, and links to anything that failed."""
    rows = ["<table><tr><th>family</th><th>pass</th><th>fail / error</th><th>skipped</th><th>studies</th>"
            "<th>failed checks</th></tr>"]
    for f in sections:
        c = [r for r in doc["checks"] if r["family"] == f]
        n = {s: sum(r["status"] == s for r in c) for s in ("pass", "fail", "error", "skipped", "study")}
        bad = [r["name"] for r in c if r["status"] in ("fail", "error")]
        links = ", ".join(f'<a href="#{_e(b)}">{_e(b)}</a>' for b in bad) or "-"
        cls = "fail" if bad else "pass"
        rows.append(f'<tr class="row {cls}"><td class="status"><a href="#family-{f}">{f}</a></td><td class="num">'
                    f'{n["pass"]}</td><td class="num">{n["fail"] + n["error"]}</td><td class="num">{n["skipped"]}</td>'
                    f'<td class="num">{n["study"]}</td><td>{links}</td></tr>')
    rows.append("</table>")
    return "<h2>Summary</h2>" + "".join(rows)


def render_html(doc: dict, results) -> str:
    by_name = {r.check.name: r for r in results}
    s = doc["summary"]
    ok = doc["exit_status"] == 0
    verdict = "all checks pass" if ok else f"{s['fail'] + s['error']} check(s) FAILED"
    sections = [f for f in FAMILIES if any(c["family"] == f for c in doc["checks"])]
    nav = "".join(f'<a href="#family-{f}">{f}</a>' for f in sections)
    nav += ('<a href="#approximations">approximations</a><a href="#performance">performance</a>'
            '<a href="#provenance">provenance</a>')
    body = [_dashboard(doc, sections)]
    for f in sections:
        rows = [c for c in doc["checks"] if c["family"] == f]
        body.append(f'<h2 id="family-{f}">{f} <span class="small">({sum(c["status"] == "pass" for c in rows)} of '
                    f'{len(rows)} pass)</span></h2>{_check_rows(rows, by_name)}')
    body.append(f'<h2 id="approximations">How wrong are the approximations?</h2>{_approximations(doc, by_name)}')
    body.append(f'<h2 id="performance">Performance</h2>{_performance(doc)}')
    body.append(f'<h2 id="provenance">Provenance</h2>{_provenance(doc)}')
    how = ("<p class='small'>How to read this report: each row is one check from the registry "
           "(<code>bsdflab.validation</code>), the same code the test suite runs. <b>measured</b> is the "
           "statistic named in the row, <b>limit</b> the tolerance it must meet; open <i>details</i> for the "
           "tolerance's derivation, the seed, the effort and the figures. Red rows failed; "
           "blue rows are studies (numbers without a pass/fail limit).</p>")
    return (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>bsdflab validation "
            f"({_e(doc['level'])})</title><style>{CSS}</style></head><body>"
            f"<header class='{'ok' if ok else 'bad'}'><h1>bsdflab validation report: {verdict}</h1>"
            f"<p>level <b>{_e(doc['level'])}</b>; {s['pass']} pass, {s['fail']} fail, {s['error']} error, "
            f"{s['skipped']} skipped, {s['study']} studies; {doc['duration_s']:.0f} s; bsdflab "
            f"{_e(doc['provenance']['versions'].get('bsdflab'))} at "
            f"{_e((doc['provenance']['git_commit'] or '?')[:10])}</p>"
            f"</header><nav>{nav}</nav><main>{how}{''.join(body)}</main></body></html>")
