#!/usr/bin/env bash
# Check a `liedyn view` page (view.html) in headless Chromium:
#   (a) the page logged "liedyn-view: loaded F frames, O objects" (with the expected F and O,
#       when given),
#   (b) no JS error was logged ("Uncaught ..." or the page's own "liedyn-view error: ..."),
#   (c) the screenshot is not blank: more than 1% of its pixels differ from the top-left one
#       (the page keeps its overlays clear of that corner, so it is the canvas background).
#
# Usage: scripts/viewer/check_view.sh VIEW_HTML OUT_PNG [EXPECTED_FRAMES [EXPECTED_OBJECTS]]
#   VIEW_HTML may end in a URL fragment with the page's options, e.g. view.html#frame=100&paused
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

[[ $# -ge 2 && $# -le 4 ]] || die "usage: $0 VIEW_HTML OUT_PNG [EXPECTED_FRAMES [EXPECTED_OBJECTS]]"
view=${1%%#*}
fragment=${1#"$view"}  # "" or "#..."
png=$2
want_frames=${3:-}
want_objects=${4:-}
[[ -f $view ]] || die "$view: no such file"
chrome=$(command -v chromium || command -v chromium-browser || true)
[[ -n $chrome ]] || die "chromium not found (apt-get install -y --no-install-recommends chromium)"

url=$(python3 -c 'import pathlib, sys; print(pathlib.Path(sys.argv[1]).resolve().as_uri())' "$view")$fragment
png_abs=$(realpath -m "$png")
mkdir -p "$(dirname "$png_abs")"
rm -f "$png_abs"
# A fresh profile each run: no lock held by another Chromium, nothing left in ~/.config.
profile=$(mktemp -d)
log=$(mktemp)
trap 'rm -rf "$profile" "$log"' EXIT

# --disable-gpu --use-gl=swiftshader --enable-unsafe-swiftshader: WebGL on the CPU (SwiftShader);
#   without the last flag Chromium 156 refuses the software WebGL fallback.
# --virtual-time-budget: the screenshot waits until the page is idle or 5 s of virtual time
#   have passed; the page draws its first frame synchronously on load anyway.
# --no-sandbox: we run as root.
start=$(date +%s%N)
status=0
timeout 300 "$chrome" --headless --no-sandbox --disable-gpu --use-gl=swiftshader \
  --enable-unsafe-swiftshader --allow-file-access-from-files --user-data-dir="$profile" \
  --enable-logging=stderr --v=0 --virtual-time-budget=5000 --window-size=800,600 \
  --hide-scrollbars --screenshot="$png_abs" "$url" >"$log" 2>&1 || status=$?
ms=$((($(date +%s%N) - start) / 1000000))
printf 'check_view: chromium took %d.%03d s (exit status %d)\n' $((ms / 1000)) $((ms % 1000)) "$status"

failed=0
console=$(grep -E '^\[[^]]*:CONSOLE[:(]' "$log" || true)
[[ $status -eq 0 ]] || fail "chromium exited with status $status"

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

# (b) JS errors
errors=$(grep -E '"(Uncaught|liedyn-view error)' <<<"$console" | sed -E 's/^\[[^]]*\] /  /' || true)
[[ -z $errors ]] || fail "JS errors logged:"$'\n'"$errors"

# (c) the screenshot
if [[ ! -s $png_abs ]]; then
  fail "no screenshot written to $png_abs"
else
  python3 - "$png_abs" <<'PY' || failed=1
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
if share <= 0.01:
    sys.exit("check_view: FAIL: the screenshot is blank (<= 1% of pixels differ from the background)")
PY
fi

if [[ $failed -ne 0 ]]; then
  echo "check_view: console messages from the page:" >&2
  sed -E 's/^\[[^]]*\] /  /' <<<"$console" >&2
  exit 1
fi
echo "check_view: OK ($view)"
