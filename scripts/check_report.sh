#!/usr/bin/env bash
# Checks that a report opens in a browser and shows its pictures:
#   scripts/check_report.sh REPORT_DIR [SCREENSHOT.png]
# Renders REPORT_DIR/report.html with headless Chromium (installed from Debian's
# `chromium` package if missing, as scripts/install_deps.sh installs packages), writes a
# screenshot of its top 1280x4000 pixels (default REPORT_DIR/report_screenshot.png), and
# fails unless the screenshot exists and every <img> of the page loaded (naturalWidth > 0).
set -euo pipefail

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 REPORT_DIR [SCREENSHOT.png]" >&2
  exit 2
fi
report_dir=$(cd "$1" && pwd)
page="$report_dir/report.html"
screenshot=${2:-"$report_dir/report_screenshot.png"}
if [ ! -f "$page" ]; then
  echo "check_report: $page: no such file" >&2
  exit 1
fi

browser=""
for candidate in chromium chromium-browser; do
  if command -v "$candidate" >/dev/null 2>&1; then browser=$candidate; break; fi
done
if [ -z "$browser" ]; then
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  echo "check_report: installing chromium"
  "${sudo_cmd[@]}" apt-get update -qq
  # Through env: sudo resets the environment, so a variable set before it would be lost.
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium
  browser=chromium
fi

# A throw-away profile, so runs do not share state or lock each other out.
profile=$(mktemp -d)
probe="$report_dir/.check_report_$$.html"
cleanup() { rm -rf "$profile" "$probe"; }
trap cleanup EXIT

run_browser() {
  # Chromium prints harmless DBus/GPU complaints on stderr in containers; keep them out
  # of the way unless it fails.
  timeout 120 "$browser" --headless --no-sandbox --disable-gpu --disable-dev-shm-usage \
    --hide-scrollbars --user-data-dir="$profile" "$@" 2>"$profile/stderr.log" || {
    status=$?
    cat "$profile/stderr.log" >&2
    return $status
  }
}

# 1. The screenshot: headless Chromium captures the window, not the whole page, so a
# report longer than 4000 px is cut off here; step 2 checks every picture regardless.
rm -f "$screenshot"
run_browser --screenshot="$screenshot" --window-size=1280,4000 "file://$page" >/dev/null
if [ ! -s "$screenshot" ]; then
  echo "check_report: no screenshot was written to $screenshot" >&2
  exit 1
fi

# 2. The images: a copy of the page beside it (so relative paths resolve the same) with
# a script that, once everything has loaded, writes the result into the DOM.
probe_script='<script>
window.addEventListener("load", function () {
  var images = Array.prototype.slice.call(document.images);
  var broken = images.filter(function (image) { return !image.complete || image.naturalWidth === 0; });
  var result = document.createElement("pre");
  result.id = "segslam-image-check";
  result.textContent = "images=" + images.length + " broken=" + broken.length +
      broken.map(function (image) { return " " + image.getAttribute("src"); }).join("");
  document.body.appendChild(result);
});
</script>'
# The script goes before the page's last </body> (at its end if it has none).
body_end=$(grep -abo '</body>' "$page" | tail -n 1 | cut -d: -f1 || true)
if [ -n "$body_end" ]; then
  { head -c "$body_end" "$page"; printf '%s' "$probe_script"; tail -c +"$((body_end + 1))" "$page"; } >"$probe"
else
  { cat "$page"; printf '%s' "$probe_script"; } >"$probe"
fi
dom=$(run_browser --dump-dom --virtual-time-budget=10000 "file://$probe")
result=$(printf '%s\n' "$dom" | grep -o 'images=[0-9]* broken=[0-9]*[^<]*' || true)
if [ -z "$result" ]; then
  echo "check_report: the page's load event never reported its images" >&2
  exit 1
fi
images=$(printf '%s' "$result" | sed -E 's/^images=([0-9]+).*/\1/')
broken=$(printf '%s' "$result" | sed -E 's/^images=[0-9]+ broken=([0-9]+).*/\1/')
if [ "$broken" != "0" ]; then
  echo "check_report: $broken of $images images did not load:$(printf '%s' "$result" | sed -E 's/^images=[0-9]+ broken=[0-9]+//')" >&2
  exit 1
fi
echo "check_report: $page renders ($screenshot), all $images images loaded"
