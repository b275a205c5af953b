#!/usr/bin/env bash
# Check a `liedyn view` page (view.html) in headless Chromium:
#   (a) the page logged "liedyn-view: loaded F frames, O objects" (with the expected F and O,
#       when given) and "liedyn-view: drawn frame K (t = T s)" (with the expected K, --drawn),
#   (b) no JS error was logged ("Uncaught ..." or the page's own "liedyn-view error: ..."),
#   (c) the screenshot is not blank: more than 1% of its pixels differ from the top-left one
#       (the page keeps its overlays clear of that corner, so it is the canvas background;
#       --sparse-ok waives this for a page that draws little, e.g. a body as a triad of lines);
#       with --clear-edges, also nothing is cut off: the outermost two pixels all round are
#       background (for a scene without planes, and its overlays hidden: hide=panel,ui,title).
# The page's warnings ("liedyn-view: warning: ...", e.g. a bad fragment option) are printed as
# "check_view: page warning: ...", and do not fail the check.
#
# Usage: scripts/viewer/check_view.sh [--size WxH] [--drawn K] [--clear-edges] [--sparse-ok]
#                                      VIEW_HTML OUT_PNG
#                                      [EXPECTED_FRAMES [EXPECTED_OBJECTS]]
#   VIEW_HTML may end in a URL fragment with the page's options (view_template.html's header),
#   e.g. view.html#frame=last&paused&hide=panel,ui
#   --size: the window, and so the screenshot, in CSS pixels (default 800x600)
#   --drawn: the frame number the page must report drawn (e.g. the run's last)
# Needs: apt-get install -y --no-install-recommends chromium   (and python3, standard library)
# Exit status: 0 all checks passed, 1 a check failed, 2 usage or setup error.
#
# Chromium (156) with --enable-logging=stderr prints each console message, whatever its level
# (log, warn, error, uncaught exception), as
#   [PID:TID:MMDD/HHMMSS.UUUUUU:INFO:CONSOLE:LINE] "MESSAGE", source: URL (LINE)
# so errors are told apart by their text, not by the level.
set -euo pipefail

die() { echo "check_view: $*" >&2; exit 2; }
fail() { echo "check_view: FAIL: $*" >&2; failed=1; }

usage="usage: $0 [--size WxH] [--drawn K] [--clear-edges] [--sparse-ok] VIEW_HTML OUT_PNG [EXPECTED_FRAMES [EXPECTED_OBJECTS]]"
size=800,600
want_drawn=
clear_edges=0
sparse_ok=0
while [[ $# -gt 0 && $1 == --* ]]; do
  case $1 in
    --size) [[ $# -ge 2 && ${2:-} =~ ^([0-9]+)x([0-9]+)$ ]] || die "--size: expected WxH, e.g. 480x360"
            size=${BASH_REMATCH[1]},${BASH_REMATCH[2]}
            shift 2 ;;
    --drawn) [[ $# -ge 2 && ${2:-} =~ ^[0-9]+$ ]] || die "--drawn: expected a frame number"
             want_drawn=$2
             shift 2 ;;
    --clear-edges) clear_edges=1
                   shift ;;
    --sparse-ok) sparse_ok=1
                 shift ;;
    *) die "$usage" ;;
  esac
done
[[ $# -ge 2 && $# -le 4 ]] || die "$usage"
view=${1%%#*}
fragment=${1#"$view"}  # "" or "#..."
png=$2
want_frames=${3:-}
want_objects=${4:-}
[[ -f $view ]] || die "$view: no such file"
source "$(dirname "${BASH_SOURCE[0]}")/../lib/headless_chromium.sh"
chromium_path >/dev/null || die "chromium not found (apt-get install -y --no-install-recommends chromium)"

url=$(python3 -c 'import pathlib, sys; print(pathlib.Path(sys.argv[1]).resolve().as_uri())' "$view")$fragment
png_abs=$(realpath -m "$png")
mkdir -p "$(dirname "$png_abs")"
rm -f "$png_abs"
log=$(mktemp)
trap 'rm -f "$log" "$log.out"' EXIT

# --disable-gpu --use-gl=swiftshader --enable-unsafe-swiftshader: WebGL on the CPU (SwiftShader);
#   without the last flag Chromium 156 refuses the software WebGL fallback.
# --virtual-time-budget: the screenshot waits until the page is idle or 5 s of virtual time
#   have passed; the page draws its first frame synchronously on load anyway.
run_headless_chromium check_view "$log" --use-gl=swiftshader --enable-unsafe-swiftshader \
  --allow-file-access-from-files --virtual-time-budget=5000 --window-size="$size" \
  --hide-scrollbars --screenshot="$png_abs" "$url"

failed=0
console=$(page_console "$log")
[[ $chromium_status -eq 0 ]] || fail "chromium exited with status $chromium_status"

# (a) the load line, and the expected counts
loaded=$(grep -oE '"liedyn-view: loaded [0-9]+ frames, [0-9]+ objects"' <<<"$console" | head -n 1 || true)
if [[ -z $loaded ]]; then
  fail 'no console line "liedyn-view: loaded F frames, O objects"'
else
  read -r frames objects < <(sed -E 's/.* ([0-9]+) frames, ([0-9]+) objects.*/\1 \2/' <<<"$loaded")
  echo "check_view: page loaded $frames frames, $objects objects"
  [[ -z $want_frames || $frames == "$want_frames" ]] || fail "expected $want_frames frames, the page has $frames"
  [[ -z $want_objects || $objects == "$want_objects" ]] || fail "expected $want_objects objects, the page has $objects"
fi

drawn=$(grep -oE '"liedyn-view: drawn frame [0-9]+ [^"]*"' <<<"$console" | head -n 1 || true)
if [[ -z $drawn ]]; then
  fail 'no console line "liedyn-view: drawn frame K (t = T s)"'
else
  read -r drawn_frame drawn_rest < <(sed -E 's/"liedyn-view: drawn frame ([0-9]+) (.*)"/\1 \2/' <<<"$drawn")
  echo "check_view: page drew frame $drawn_frame $drawn_rest"
  [[ -z $want_drawn || $drawn_frame == "$want_drawn" ]] || fail "expected frame $want_drawn drawn, the page drew $drawn_frame"
fi
grep -oE '"liedyn-view: warning: .*", source:' <<<"$console" |
  sed -E 's/^"liedyn-view: warning: (.*)", source:$/check_view: page warning: \1/' || true

# (b) JS errors
errors=$(grep -E '"(Uncaught|liedyn-view error)' <<<"$console" | sed -E 's/^\[[^]]*\] /  /' || true)
[[ -z $errors ]] || fail "JS errors logged:"$'\n'"$errors"

# (c) the screenshot
if [[ ! -s $png_abs ]]; then
  fail "no screenshot written to $png_abs"
else
  python3 - "$png_abs" "$clear_edges" "$sparse_ok" <<'PY' || failed=1
# A PNG reader on the standard library only (zlib): 8-bit RGB or RGBA, not interlaced, which
# is what Chromium writes.
import struct, sys, zlib

path = sys.argv[1]
data = open(path, "rb").read()
if data[:8] != b"\x89PNG\r\n\x1a\n":
    sys.exit(f"check_view: FAIL: {path} is not a PNG")
pos, idat, ihdr = 8, [], None
while pos < len(data):
    length, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + length]
    if kind == b"IHDR":
        ihdr = struct.unpack(">IIBBBBB", body)
    elif kind == b"IDAT":
        idat.append(body)
    elif kind == b"IEND":
        break
    pos += 12 + length
width, height, depth, colour, _, _, interlace = ihdr
channels = {2: 3, 6: 4}.get(colour)
if depth != 8 or channels is None or interlace:
    sys.exit(f"check_view: FAIL: unsupported PNG (bit depth {depth}, colour type {colour}, interlace {interlace})")
raw = zlib.decompress(b"".join(idat))
bpp, stride = channels, width * channels
prev = bytearray(stride)
rows = []
for y in range(height):
    start = y * (stride + 1)
    kind, line = raw[start], bytearray(raw[start + 1:start + 1 + stride])
    if kind == 1:    # Sub
        for i in range(bpp, stride):
            line[i] = (line[i] + line[i - bpp]) & 255
    elif kind == 2:  # Up
        for i in range(stride):
            line[i] = (line[i] + prev[i]) & 255
    elif kind == 3:  # Average
        for i in range(stride):
            left = line[i - bpp] if i >= bpp else 0
            line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
    elif kind == 4:  # Paeth
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], (prev[i - bpp] if i >= bpp else 0)
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line)
    prev = line
# Compare RGB only: the alpha of a screenshot is opaque everywhere.
background = bytes(rows[0][0:3])
differing = sum(1 for line in rows for i in range(0, stride, bpp) if line[i:i + 3] != background)
share = differing / (width * height)
print(f"check_view: screenshot {width}x{height}, {100 * share:.1f}% of pixels differ from the "
      f"background rgb{tuple(background)}")
if share <= 0.01 and sys.argv[3] != "1":
    sys.exit("check_view: FAIL: the screenshot is blank (<= 1% of pixels differ from the background)")
if sys.argv[2] == "1":
    edge = [(x, y) for y in range(height) for x in range(width)
            if min(x, y, width - 1 - x, height - 1 - y) < 2 and rows[y][bpp * x:bpp * x + 3] != background]
    if edge:
        sys.exit(f"check_view: FAIL: {len(edge)} pixels of the outermost two rows and columns are not "
                 f"background (the scene is cut off), e.g. at x, y = {edge[0]}")
    print("check_view: nothing drawn within 2 pixels of the edges")
PY
fi

if [[ $failed -ne 0 ]]; then
  echo "check_view: console messages from the page:" >&2
  sed -E 's/^\[[^]]*\] /  /' <<<"$console" >&2
  exit 1
fi
echo "check_view: OK ($view)"
