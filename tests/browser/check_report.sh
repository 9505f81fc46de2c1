#!/usr/bin/env bash
# Opens a `cargo xtask compare` run's report.html in headless Chromium, as a reader's browser
# would (file://, no network), and checks what the reader would see: the page finished loading,
# every picture in it decoded (none broken), every chart is there with its points, and no
# script error or console error. Then takes a screenshot.
#
#   tests/browser/check_report.sh DIR [SCREENSHOT.png]
#
# Chromium: $CHROMIUM, else `chromium` on the PATH (Debian: apt-get install chromium). As
# root, on a machine without Chromium, it is installed with apt-get.
set -euo pipefail
dir=${1:?usage: check_report.sh DIR [SCREENSHOT.png]}
shot=${2:-$dir/report-screenshot.png}
page="$(cd "$dir" && pwd)/report.html"
test -s "$page" || { echo "check_report: no $page" >&2; exit 1; }
browser=${CHROMIUM:-$(command -v chromium || true)}
if [ -z "$browser" ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
        browser=$(command -v chromium)
    else
        echo "check_report: no Chromium (set CHROMIUM, or apt-get install chromium)" >&2
        exit 1
    fi
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The flags of a closed network (no background connections, no first-run work).
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
    --disable-background-networking --disable-component-update --disable-sync
    --user-data-dir="$work/profile" --virtual-time-budget=15000)
"$browser" "${flags[@]}" --enable-logging=stderr --v=0 --dump-dom "file://$page" \
    >"$work/dom.html" 2>"$work/console.log" || {
    echo "check_report: Chromium failed:" >&2
    tail -20 "$work/console.log" >&2
    exit 1
}
python3 "$(dirname "$0")/check_dom.py" "$page" "$work/dom.html" "$work/console.log"
"$browser" "${flags[@]}" --window-size=1400,2600 --screenshot="$shot" "file://$page" \
    >/dev/null 2>"$work/shot.log" || {
    echo "check_report: the screenshot failed:" >&2
    tail -20 "$work/shot.log" >&2
    exit 1
}
test -s "$shot" || { echo "check_report: no screenshot written" >&2; exit 1; }
echo "check_report: screenshot $shot"
