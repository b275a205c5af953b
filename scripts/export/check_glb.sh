#!/usr/bin/env bash
# Load a `liedyn export --format gltf` file (run.glb) with three.js's GLTFLoader (r111, Debian's
# libjs-three) in headless Chromium, as a glTF consumer other than our own reader would:
#   (a) the page logged "liedyn-glb: loaded N nodes, A animations, T tracks" (with the
#       expected counts, when given), after playing the animation to its middle and finding
#       every node's position finite,
#   (b) no JS error was logged ("Uncaught ..." or the page's own "liedyn-glb error: ...").
# The page inlines three.min.js, GLTFLoader.js and the glb (base64), and calls
# GLTFLoader.parse: nothing is fetched. N counts the objects under the loaded scene (one per
# glTF node), T the tracks of all animation clips.
#
# Usage: scripts/export/check_glb.sh RUN_GLB [EXPECTED_NODES [EXPECTED_ANIMATIONS [EXPECTED_TRACKS]]]
# Needs: chromium and libjs-three (apt-get install -y --no-install-recommends chromium libjs-three)
# and python3 (standard library).
# Exit status: 0 all checks passed, 1 a check failed, 2 usage error, 77 chromium or
# libjs-three missing (ctest's SKIP_RETURN_CODE).
set -euo pipefail

die() { echo "check_glb: $*" >&2; exit 2; }
skip() { echo "check_glb: SKIPPED: $*" >&2; exit 77; }

[[ $# -ge 1 && $# -le 4 ]] || die "usage: $0 RUN_GLB [EXPECTED_NODES [EXPECTED_ANIMATIONS [EXPECTED_TRACKS]]]"
glb=$1
want_nodes=${2:-}
want_animations=${3:-}
want_tracks=${4:-}
[[ -f $glb ]] || die "$glb: no such file"
three_dir=${LIEDYN_THREE_DIR:-/usr/share/javascript/three}
three=$three_dir/three.min.js
loader=$three_dir/examples/js/loaders/GLTFLoader.js
source "$(dirname "${BASH_SOURCE[0]}")/../lib/headless_chromium.sh"
chromium_path >/dev/null || skip "chromium not found (apt-get install -y --no-install-recommends chromium)"
[[ -f $three && -f $loader ]] || skip "$three or $loader missing (apt-get install -y libjs-three)"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
page=$work/check_glb.html
# Inlined script text must not end its <script> element early: every "</script", in any
# letter case, becomes "<\/script" (as problems/view.cpp does; the same text to JavaScript
# inside a string, regex or comment).
python3 - "$three" "$loader" "$glb" "$page" <<'PY'
import base64, re, sys
three, loader, glb, page = sys.argv[1:5]
def script(path):
    return re.sub(r"</(script)", r"<\\/\1", open(path, encoding="utf-8").read(), flags=re.IGNORECASE)
data = base64.b64encode(open(glb, "rb").read()).decode("ascii")
html = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>check_glb</title></head><body>
<script>{script(three)}</script>
<script>{script(loader)}</script>
<script id="glb" type="application/octet-stream">{data}</script>
<script>
(function () {{
  function fail(message) {{ console.error('liedyn-glb error: ' + message); }}
  try {{
    var start = performance.now();
    var text = atob(document.getElementById('glb').textContent);
    var bytes = new Uint8Array(text.length);
    for (var i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    new THREE.GLTFLoader().parse(bytes.buffer, '', function (gltf) {{
      var nodes = 0, tracks = 0, duration = 0;
      gltf.scene.traverse(function (o) {{ if (o !== gltf.scene) nodes++; }});
      gltf.animations.forEach(function (clip) {{ tracks += clip.tracks.length; duration = Math.max(duration, clip.duration); }});
      var mixer = new THREE.AnimationMixer(gltf.scene);
      gltf.animations.forEach(function (clip) {{ mixer.clipAction(clip).play(); }});
      mixer.setTime(duration / 2);
      var bad = 0;
      gltf.scene.traverse(function (o) {{
        if (![o.position.x, o.position.y, o.position.z, o.quaternion.w, o.scale.z].every(isFinite)) bad++;
      }});
      if (bad) fail(bad + ' nodes have a non-finite pose halfway through the animation');
      console.log('liedyn-glb: loaded ' + nodes + ' nodes, ' + gltf.animations.length + ' animations, ' +
                  tracks + ' tracks, ' + duration.toFixed(6) + ' s, in ' + (performance.now() - start).toFixed(0) + ' ms');
    }}, function (error) {{ fail(String(error && error.message || error)); }});
  }} catch (e) {{ fail(String(e && e.message || e)); }}
}})();
</script></body></html>"""
open(page, "w", encoding="utf-8").write(html)
PY

url=$(python3 -c 'import pathlib, sys; print(pathlib.Path(sys.argv[1]).resolve().as_uri())' "$page")
log=$work/chromium.log
# --dump-dom returns once the page's scripts have run (parse is synchronous for a glb without
# external resources).
run_headless_chromium check_glb "$log" --virtual-time-budget=10000 --dump-dom "$url"

failed=0
fail() { echo "check_glb: FAIL: $*" >&2; failed=1; }
console=$(page_console "$log")
[[ $chromium_status -eq 0 ]] || fail "chromium exited with status $chromium_status"
loaded=$(grep -oE '"liedyn-glb: loaded [0-9]+ nodes, [0-9]+ animations, [0-9]+ tracks[^"]*"' <<<"$console" | head -n 1 || true)
if [[ -z $loaded ]]; then
  fail 'no console line "liedyn-glb: loaded N nodes, A animations, T tracks"'
else
  echo "check_glb: ${loaded//\"/}"
  read -r nodes animations tracks < <(sed -E 's/.* ([0-9]+) nodes, ([0-9]+) animations, ([0-9]+) tracks.*/\1 \2 \3/' <<<"$loaded")
  [[ -z $want_nodes || $nodes == "$want_nodes" ]] || fail "expected $want_nodes nodes, GLTFLoader has $nodes"
  [[ -z $want_animations || $animations == "$want_animations" ]] || fail "expected $want_animations animations, GLTFLoader has $animations"
  [[ -z $want_tracks || $tracks == "$want_tracks" ]] || fail "expected $want_tracks tracks, GLTFLoader has $tracks"
fi
errors=$(grep -E '"(Uncaught|liedyn-glb error)' <<<"$console" | sed -E 's/^\[[^]]*\] /  /' || true)
[[ -z $errors ]] || fail "JS errors logged:"$'\n'"$errors"
if [[ $failed -ne 0 ]]; then
  echo "check_glb: console messages from the page:" >&2
  sed -E 's/^\[[^]]*\] /  /' <<<"$console" >&2
  exit 1
fi
echo "check_glb: OK ($glb)"
