#!/usr/bin/python3
"""gesweep report: an HTML page of figures and tables from one or more archives (docs/report.md).

    /usr/bin/python3 scripts/report/report.py -o DIR [--title T] [--quiet] -- ARCHIVE...

Normally run by `gesweep report ARCHIVE... -o DIR`, which checks the archives first. Writes
DIR/index.html and the figures (PNG) beside it; the page has no script and no external resource, so it
opens from disk. Exit codes: 0 ok, 2 bad input (one line on stderr), 1 anything else.
"""

import argparse
import html
import os
import re
import shutil
import sys
import time

import numpy as np

import figures_common
import report_claims
import report_figures
import report_labels
from report_data import open_archives

CSS = """
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; margin: 2em auto; max-width: 1200px;
       color: #1d1d1d; line-height: 1.45; padding: 0 1em; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { margin-top: 2em; border-bottom: 1px solid #ccc; }
.sub { color: #555; margin-top: 0; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { color: #444; font-size: 0.92em; margin-top: 0.4em; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: left; vertical-align: top; }
th { background: #f0f0f0; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
.agrees { background: #e3f4e1; } .differs { background: #fbe3e0; } .nodata { background: #f3f3f3; color: #666; }
pre { background: #f7f7f7; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
details { margin: 0.5em 0; } summary { cursor: pointer; }
nav a { margin-right: 1em; } nav a.absent { color: #888; }
p.absent { color: #555; font-style: italic; }
table.claims { width: 100%; } table.claims td:nth-child(1) { width: 22%; } table.claims td:nth-child(2) { width: 18%; }
table.claims td:nth-child(3) { width: 42%; } td.claim-engine ul { margin: 0.3em 0 0 1.2em; padding: 0; }
td .source { color: #666; font-size: 0.9em; }
div.long { max-height: 36em; overflow-y: auto; display: inline-block; border: 1px solid #ccc; }
div.long table { margin: 0; } div.long th { position: sticky; top: 0; }
@media print { div.long { max-height: none; overflow: visible; } }
"""

# A table of more rows than this scrolls inside a box (every row is in the page, none behind a click).
LONG_TABLE_ROWS = 40


def esc(value):
    return html.escape(str(value))


def table(headers, rows, numeric=()):
    out = ["<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in headers) + "</tr>"]
    for row in rows:
        cells = []
        for i, cell in enumerate(row):
            cls = ' class="num"' if i in numeric else ""
            cells.append(f"<td{cls}>{esc(cell)}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def fmt(value, digits=5):
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "—"
    return f"{value:.{digits}g}"


def boundary_section(archives):
    parts = []
    for archive in archives:
        boundary = archive.boundary()
        if boundary is None:
            continue
        keys = boundary["keys"]
        headers = keys + ["H* (m)", "H*/b", "grid bracket (m)", "note"]
        rows = []
        for i in range(len(boundary["height_m"])):
            row = []
            for k in keys:
                levels = boundary["levels"].get(k) or []
                v = float(boundary[k][i])
                # A level in words (report_labels); a number exact, as the archive holds it.
                row.append(report_labels.value_label(k, v, levels) if levels else fmt(v, 7))
            lower, upper = boundary["grid_lower_height_m"][i], boundary["grid_upper_height_m"][i]
            row += [fmt(float(boundary["height_m"][i]), 7), fmt(float(boundary["height_over_span"][i]), 4),
                    f"{lower:.5g} – {upper:.5g}" if np.isfinite(lower) else "", boundary["reason"][i]]
            rows.append(row)
        found = np.isfinite(boundary["height_m"])
        summary = f"{int(found.sum())} of {len(found)} points have a boundary"
        if found.any():
            ratio = boundary["height_over_span"][found]
            summary += f"; H*/b from {np.min(ratio):.4f} to {np.max(ratio):.4f}"
            if "speed_mps" in keys:
                speeds = boundary["speed_mps"][found]
                summary += (f" (lowest at {speeds[np.argmin(ratio)]:.4g} m/s, highest at "
                            f"{speeds[np.argmax(ratio)]:.4g} m/s)")
        attrs = boundary["attrs"]
        parts.append(f"<h3>{esc(archive.study_name)} <small>({esc(os.path.basename(archive.path))})</small></h3>"
                     f"<p>{esc(summary)}. Refined to {fmt(float(attrs.get('tolerance_m', float('nan'))) * 1000, 3)} mm "
                     f"on each run's continuous model; b = {fmt(float(attrs.get('wingspan_m', float('nan'))), 5)} m. "
                     f"Written by <code>{esc(attrs.get('command_line', ''))}</code> on {esc(attrs.get('created', ''))}."
                     f"</p>")
        # Every point in view, not behind a click: a long table scrolls inside its box, headers kept.
        rendered = table(headers, rows, numeric=set(range(len(keys) + 2)))
        parts.append(f'<div class="long">{rendered}</div>' if len(rows) > LONG_TABLE_ROWS else rendered)
    return "\n".join(parts)


# The claims table's per-run evidence lists at most this many lines (then says how many more).
MAX_CLAIM_DETAILS = 40


def claim_engine_cell(claim):
    """The engine's side of a claim: its few lines, the archives read, and the per-run evidence
    collapsed in a <details> block."""
    text = "<br>".join(esc(line) for line in claim.engine.split("\n"))
    if claim.sources:
        text += f'<br><span class="source">from {esc(", ".join(claim.sources))}</span>'
    if claim.details:
        shown = claim.details[:MAX_CLAIM_DETAILS]
        more = len(claim.details) - len(shown)
        items = "".join(f"<li>{esc(line)}</li>" for line in shown) + (f"<li>… and {more} more</li>" if more else "")
        text += (f"<details><summary>the {len(claim.details)} run(s) behind it</summary><ul>{items}</ul>"
                 f"</details>")
    return text


def claims_section(archives):
    rows = report_claims.paper_claims(archives)
    if not rows:
        return ""
    out = ['<table class="claims"><tr><th>claim</th><th>paper</th><th>engine (from the archives)</th><th>verdict</th>'
           "</tr>"]
    for claim in rows:
        verdict = claim.verdict
        cls = "agrees" if verdict == "agrees" else ("nodata" if verdict == "no data" else "differs")
        out.append(f"<tr><td>{esc(claim.claim)}</td><td>{esc(claim.paper)}</td>"
                   f'<td class="claim-engine">{claim_engine_cell(claim)}</td><td class="{cls}">{esc(verdict)}</td></tr>')
    out.append("</table>")
    return "\n".join(out)


def status_section(archives):
    rows = []
    for archive in archives:
        ok, failed, pending = archive.counts()
        rows.append([os.path.basename(archive.path), archive.study_name, archive.run_count, ok, failed, pending,
                     "yes (being written, or its writer died)" if archive.snapshot else "no",
                     "; ".join(archive.notes)])
    # notes: what the engine's check could not check (gesweep check; an archive merged before shard
    # identities, say), as every gesweep command prints it.
    return table(["archive", "study", "runs", "ok", "failed", "pending", "snapshot", "notes"], rows,
                 numeric={2, 3, 4, 5})


def risk_status_section(risks):
    """The landings of each subset-simulation archive by status (none is pending: the archive is written whole)."""
    if not risks:
        return ""
    rows = []
    for archive in risks:
        ok, failed, _ = archive.counts()
        rows.append([os.path.basename(archive.path), archive.study_name, archive.run_count, ok, failed])
    return "<p>Landings of the subset simulations (gesweep risk):</p>" + table(
        ["archive", "study", "landings", "ok", "failed"], rows, numeric={2, 3, 4})


PROVENANCE_KEYS = ["study_name", "study_description", "study_path", "study_fingerprint", "aircraft_name",
                   "aircraft_path", "analyses", "engine_version", "git_commit", "compiler", "hdf5_version", "host",
                   "threads", "command_line", "shard", "start_time", "end_time", "resumed_at", "complete",
                   "merged_from"]


def provenance_section(archives):
    parts = []
    for archive in archives:
        rows = []
        for key in PROVENANCE_KEYS:
            if key in archive.attrs:
                value = archive.attrs[key]
                if isinstance(value, list):
                    value = ", ".join(str(v) for v in value) or "—"
                rows.append([key, value])
        study_text = archive.attrs.get("study_text", "")
        parts.append(f"<details><summary>{esc(os.path.basename(archive.path))}: study {esc(archive.study_name)}, "
                     f"engine {esc(archive.attrs.get('engine_version', '?'))} "
                     f"({esc(archive.attrs.get('git_commit', '?'))})</summary>"
                     f"<p>File: <code>{esc(os.path.abspath(archive.path))}</code></p>"
                     f"{table(['attribute', 'value'], rows)}"
                     f"<details><summary>study file as run</summary><pre>{esc(study_text)}</pre></details>"
                     f"</details>")
    return "\n".join(parts)


def figure_html(figure):
    anchor = "figure-" + os.path.splitext(figure.file)[0]
    # The image links to itself: a figure wider than the page is shown scaled, one click gives it full size.
    return (f'<figure id="{esc(anchor)}"><a href="{esc(figure.file)}"><img src="{esc(figure.file)}" '
            f'alt="{esc(figure.title)}"></a>'
            f"<figcaption><b>{esc(figure.title)}.</b> {esc(figure.caption)}</figcaption></figure>")


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--title", default="")
    parser.add_argument("--quiet", action="store_true")
    parser.add_argument("archives", nargs="+")
    args = parser.parse_args(argv)
    started = time.time()

    def progress(text):
        if not args.quiet:
            print(f"gesweep report: {text} ({time.time() - started:.1f} s)", file=sys.stderr)

    try:
        archives = open_archives(args.archives)
    except (OSError, ValueError) as error:
        print(f"gesweep: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    created = not os.path.exists(args.output)
    os.makedirs(args.output, exist_ok=True)
    try:
        return write_report(args, archives, progress)
    except Exception as error:  # a defect of the report: one line, and nothing half-made left behind
        if created:
            shutil.rmtree(args.output, ignore_errors=True)
        print(f"gesweep: error: the report failed ({type(error).__name__}: {' '.join(str(error).split())}); "
              f"rerun with GESWEEP_REPORT_TRACEBACK=1 for the traceback", file=sys.stderr)
        if os.environ.get("GESWEEP_REPORT_TRACEBACK"):
            raise
        return 1


def absent(text):
    """A section whose data no archive holds: one line saying so (`...` as code)."""
    return '<p class="absent">' + re.sub(r"`([^`]+)`", r"<code>\1</code>", esc(text)) + "</p>"


def figure_sections(archives, outdir, progress):
    """(title, anchor, html, present) of every figure family, in page order (report_figures)."""
    sections = []
    for family in report_figures.families():
        figures = family.draw(archives, outdir)
        progress(f"{family.title.lower()}: {len(figures)} figure(s)")
        content = "\n".join(figure_html(f) for f in figures) if figures else absent(family.absent)
        sections.append((family.title, family.anchor, content, bool(figures)))
    return sections


def write_report(args, archives, progress):
    # Figures of an earlier report in DIR that this one does not draw would be stale: remove ours.
    prefixes = tuple(family.prefix for family in report_figures.families())
    for name in os.listdir(args.output):
        if name.endswith(".png") and name.startswith(prefixes):
            os.remove(os.path.join(args.output, name))
    drawn = []
    figures_common.observers.append(lambda fig, name: drawn.append(name))
    sections = figure_sections(archives, args.output, progress)
    risks = [a for a in archives if a.is_risk]
    archives = [a for a in archives if not a.is_risk]  # the sections below read sweep archives
    boundary = boundary_section(archives)
    sections.insert(1, ("Stability boundary per speed", "boundary", boundary or absent(
        "No archive of this report has a refined boundary (/analysis/boundary); `gesweep boundary --archive "
        "ARCHIVE` writes it for a modes sweep over height."), bool(boundary)))
    claims = claims_section(archives)
    sections.append(("The paper's claims beside the engine's findings", "claims",
                     ("<p>The paper: González, Boschetti, Cárdenas and Rodriguez-Celi, <i>Dynamic Ground Effect on "
                      "the Longitudinal Stability of Airplanes during the Landing</i>, Section IV and Fig. 4–9. "
                      "The engine's side is read from the archives of this report, each claim from the archives it "
                      "is about.</p>" + claims) if claims else absent(
                         "No archive of this report is of the ANCE, the airplane the paper's claims are about."),
                     bool(claims)))
    sections.append(("Runs by status", "status", status_section(archives) + risk_status_section(risks), True))
    sections.append(("Provenance", "provenance", provenance_section(archives + risks), True))

    studies = ", ".join(a.study_name for a in archives + risks)
    aircraft = sorted({a.aircraft.name for a in archives if a.aircraft.name})
    title = args.title or f"gesweep report: {', '.join(aircraft) or 'archives'}"
    nav = " ".join(f'<a href="#{anchor}"' + ("" if present else ' class="absent"') + f">{esc(name)}</a>"
                   for name, anchor, _, present in sections)
    body = "\n".join(f'<h2 id="{anchor}">{esc(name)}</h2>\n{content}' for name, anchor, content, _ in sections)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{esc(title)}</title>
<style>{CSS}</style></head>
<body>
<h1>{esc(title)}</h1>
<p class="sub">{len(archives) + len(risks)} archive(s) (studies {esc(studies)});
written {esc(time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime()))} by <code>gesweep report</code>.</p>
<nav>{nav}</nav>
{body}
</body></html>
"""
    path = os.path.join(args.output, "index.html")
    with open(path + ".partial", "w", encoding="utf-8") as out:
        out.write(page)
    os.replace(path + ".partial", path)
    for archive in archives + risks:
        archive.close()
    progress(f"wrote {path} with {len(drawn)} figure(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
