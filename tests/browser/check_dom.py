"""Checks the DOM Chromium dumped after loading report.html (see check_report.sh).

The page (crates/compare/src/html) writes on <body> what it saw as it loaded: data-ready,
data-images, data-broken, data-charts, data-points, data-errors. Those are checked against
counts taken here from the file itself (every <img> and every chart in the source must have
loaded), and the browser's console log must hold no error.

    python3 check_dom.py REPORT.html DOM.html CONSOLE.log
"""

import re
import sys


def main(source_path, dom_path, console_path):
    source = open(source_path, encoding="utf-8").read()
    dom = open(dom_path, encoding="utf-8").read()
    console = open(console_path, encoding="utf-8", errors="replace").read()
    body = re.search(r"<body([^>]*)>", dom)
    if not body:
        return ["no <body> in the dumped DOM"]
    attrs = dict(re.findall(r'data-([a-z]+)="([^"]*)"', body.group(1)))
    bad = []
    if attrs.get("ready") != "1":
        bad.append(f"the page did not finish loading (body attributes {attrs})")
    want_images = len(re.findall(r"<img\b", source))
    want_charts = len(re.findall(r'<svg class="chart"', source))
    want_points = len(re.findall(r"<circle\b", source))
    if int(attrs.get("images", -1)) != want_images:
        bad.append(f"{attrs.get('images')} pictures in the page, {want_images} in the file")
    if attrs.get("broken") != "0":
        bad.append(f"{attrs.get('broken')} broken picture(s)")
    if int(attrs.get("charts", -1)) != want_charts:
        bad.append(f"{attrs.get('charts')} charts shown, {want_charts} in the file")
    if int(attrs.get("points", -1)) != want_points:
        bad.append(f"{attrs.get('points')} chart points shown, {want_points} in the file")
    if attrs.get("errors") != "0":
        bad.append(f"{attrs.get('errors')} script error(s)")
    for line in console.splitlines():
        if "CONSOLE" in line and ("ERROR" in line or "Uncaught" in line):
            bad.append("console: " + line.strip())
    verdict = "all loaded" if not bad else "NOT all loaded"
    print(
        f"check_dom: {want_images} pictures, {want_charts} charts, {want_points} chart points "
        f"in the file ({len(source) / 1e6:.1f} MB): {verdict}"
    )
    return bad


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    problems = main(*sys.argv[1:])
    for p in problems:
        print("check_dom:", p, file=sys.stderr)
    sys.exit(1 if problems else 0)
