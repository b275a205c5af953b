#!/usr/bin/env bash
# The gallery of the bundled scenes: for each scene under problems/scenes/, a picture of its
# last frame as `liedyn view` draws it, docs/figures/scenes/<path, "/" as "-">.png, and the
# index docs/figures/scenes/README.md (picture, scene, its description's first sentence, what
# was simulated, the command that reproduces it). A scene whose run fails, stops short or does
# not converge is listed with the reason (and the picture of what was written), not left out.
#
# Usage: bash scripts/gallery.sh [--only REGEX]
#   --only: only the scenes whose path under problems/scenes/ matches the extended regex, e.g.
#           'contact/' or 'letter_(A|S)'; the index keeps the rows of the others.
#   LIEDYN: the liedyn binary (default: build/liedyn)
#   GALLERY_TIMEOUT: seconds one scene's run may take (default 240) before it is listed as
#           not finished
# Needs chromium and python3 (scripts/viewer/check_view.sh).
#
# Each run: `liedyn simulate SCENE --out TMP --every N` with about a hundred written frames
# (the picture needs the last one; the others only set the camera, which frames the whole
# run), then `liedyn view TMP` and a 480x360 screenshot of
# view.html#frame=last&paused&hide=panel,ui,title (and a scene's `framing` below) in headless
# Chromium. Simulation and drawing are deterministic (a second run of all scenes rewrote no
# byte), and a picture is only copied when its bytes change.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
liedyn=${LIEDYN:-$root/build/liedyn}
limit=${GALLERY_TIMEOUT:-240}
only=
while [[ $# -gt 0 ]]; do
  case $1 in
    --only) [[ $# -ge 2 ]] || { echo "gallery: --only needs a REGEX" >&2; exit 2; }
            only=$2; shift 2 ;;
    *) echo "usage: bash scripts/gallery.sh [--only REGEX]" >&2; exit 2 ;;
  esac
done
[[ -x $liedyn ]] || { echo "gallery: $liedyn is not built (cmake --build build), or set LIEDYN" >&2; exit 2; }
out=$root/docs/figures/scenes
mkdir -p "$out"

# Scenes whose full run takes over a minute on the reference machine (2 cores, Release), with
# the settings that shorten them; the index says what was cut.
declare -A shorten=(
  # 600 frames: 163 s with the machine half busy (the links wind onto the drum late); 200: 13 s
  [contact/spool_chain.json]="frames=200"
)

# Scenes whose objects end up small in the frame of the whole run (a die thrown across a
# table, a rope piled up under where it hung): their picture fits the last frame's bodies and
# rods instead, from further off so that what is around them shows. The index says so.
declare -A framing=(
  [contact/die_throw.json]="fit=frame&zoom=0.5"
  [contact/mesh_slab.json]="fit=frame&zoom=0.5"
  [contact/rod_coil.json]="fit=frame&zoom=0.7"
  [free_body_symmetric.json]="fit=frame"
  [helix_perversion.json]="fit=frame&zoom=0.7"
  [optimization/die_throw.json]="fit=frame"
  [optimization/die_throw_contact.json]="fit=frame&zoom=0.5"
)

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/rows"

mapfile -t scenes < <(cd "$root/problems/scenes" && find . -name '*.json' | sed 's|^\./||' | LC_ALL=C sort)
ran=0
start_all=$(date +%s)
for rel in "${scenes[@]}"; do
  [[ -z $only ]] || grep -Eq -- "$only" <<<"$rel" || continue
  ran=$((ran + 1))
  name=${rel%.json}
  name=${name//\//-}
  scene=problems/scenes/$rel
  sets=()
  for s in ${shorten[$rel]:-}; do sets+=(--set "$s"); done
  # About a hundred written frames: frames after the --set, as the run will see them.
  frames=$(python3 - "$root/$scene" "${shorten[$rel]:-}" <<'PY'
import json, sys
frames = json.load(open(sys.argv[1]))["frames"]
for s in sys.argv[2].split():
    key, _, value = s.partition("=")
    if key == "frames":
        frames = int(value)
print(frames)
PY
)
  every=$(((frames + 99) / 100))
  run=$tmp/run-$name
  cmd=(simulate "$scene" --out "$run" --every "$every" --quiet "${sets[@]}")
  t0=$(date +%s.%N)
  status=0
  (cd "$root" && timeout "$limit" "$liedyn" "${cmd[@]}") >"$tmp/sim.out" 2>"$tmp/sim.err" || status=$?
  seconds=$(python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f}')" "$t0" "$(date +%s.%N)")

  picture=no
  shot_note=
  last=
  last_time=
  if [[ -s $run/trajectory.csv ]]; then
    IFS=, read -r last last_time _ < <(tail -n 1 "$run/trajectory.csv")
    if "$liedyn" view "$run" >"$tmp/view.out" 2>&1 &&
       bash "$root/scripts/viewer/check_view.sh" --size 480x360 --drawn "$last" --sparse-ok \
         "$run/view.html#frame=last&paused&hide=panel,ui,title${framing[$rel]:+&${framing[$rel]}}" \
         "$tmp/shot.png" >"$tmp/check.out" 2>&1; then
      picture=yes
      cmp -s "$tmp/shot.png" "$out/$name.png" || cp "$tmp/shot.png" "$out/$name.png"
    else
      shot_note=$(grep -E 'FAIL|error' "$tmp/view.out" "$tmp/check.out" | head -n 1 | sed -E 's/^[^:]*://' || true)
    fi
  fi
  [[ $picture == yes ]] || rm -f "$out/$name.png"

  # The index row, from the scene file, the run's summary and its files.
  python3 - "$root" "$rel" "$name" "$status" "$limit" "$picture" "$shot_note" "$every" \
    "$last" "$last_time" "$tmp/sim.out" "$tmp/sim.err" "${shorten[$rel]:-}" "$run/shapes.json" \
    "${framing[$rel]:-}" >"$tmp/rows/$name.md" <<'PY'
import json, re, sys
(root, rel, name, status, limit, picture, shot_note, every, last_frame, last_time, sim_out, sim_err,
 settings, shapes, framing) = sys.argv[1:16]
status = int(status)
scene = json.load(open(f"{root}/problems/scenes/{rel}"))

def cell(text):
    return text.replace("|", "\\|")

def one_line(text, most=200):
    """The first sentence (not cut at "Fig. 4" or "e.g. x"); past `most` characters, cut at the
    last clause boundary outside parentheses before it."""
    text = " ".join(str(text).split())
    m = re.search(r"(?<!\bFig)(?<!\be\.g)(?<!\bi\.e)(?<!\bcf)(?<!\bvs)\.\s+(?=[A-Z0-9(])", text)
    if m:
        text = text[:m.start() + 1]
    if len(text) <= most:
        return text
    depth, cut = 0, text.rfind(" ", 0, most)
    for i, c in enumerate(text[:most]):
        depth += (c == "(") - (c == ")")
        if depth == 0 and text.startswith((", ", "; ", ": "), i):
            cut = i
    return text[:cut] + " …"

description = one_line(scene.get("title") or scene.get("description") or "")
static = scene.get("mode") == "static"
summary = open(sim_out).read()
m = re.search(r"^frames\s+(\d+) of (\d+) solved", summary, re.M)
done, requested = (int(m.group(1)), int(m.group(2))) if m else (0, int(scene["frames"]))
notes = []
full = int(scene["frames"])
if requested != full:
    notes.append(f"**shortened**: {requested} of the scene's {full} "
                 f"{'load steps' if static else 'frames'} (the full run takes over a minute)")
try:
    bodies = json.load(open(shapes))["bodies"]
except OSError:
    bodies = []
triads = [b["name"] for b in bodies if b["shape"]["type"] == "axes"]
if triads:
    notes.append(f"{', '.join(triads)}: no solid or contact samples, drawn as a triad")
if framing and picture == "yes":
    notes.append(f"the picture adds `&{framing}` to the fragment: the last frame's bodies and rods "
                 "fitted, as they are small in the whole run's frame")
if "optimization" in scene:
    notes.append("the forward run at the scene's initial parameters, not optimised")
if status == 3:
    m = re.search(r"^unconverged\s+(\d+) steps", summary, re.M)
    count = m.group(1) if m else "some"
    notes.append(f"**did not converge**: {count} of {done} steps ended short of the tolerance (exit 3)")
elif status == 4:
    failure = open(sim_err).read().strip().splitlines()
    notes.append("**failed** (exit 4): " + (failure[-1].removeprefix("liedyn: ") if failure else "a step failed")
                 + "; the picture is the last frame written")
elif status == 124:
    notes.append(f"**not finished** within {limit} s: no picture")
elif status != 0:
    error = open(sim_err).read().strip().splitlines()
    notes.append(f"**could not run** (exit {status}): " + (error[-1] if error else "no message"))
if picture != "yes" and status in (0, 3, 4):
    notes.append("**no picture**: " + (shot_note.strip() or "the page did not draw"))

if not last_frame:
    simulated = "nothing written"
elif static:
    simulated = f"{last_frame} load steps (static)"
else:
    simulated = f"{last_frame} frames, t = {float(last_time):.4g} s"
command = f"liedyn simulate problems/scenes/{rel} --out out --every {every}"
command += "".join(f" --set {s}" for s in settings.split())
image = f'<img src="{name}.png" width="240" alt="{rel}">' if picture == "yes" else "–"
what = "; ".join([simulated] + notes)
print(f"| {image} | [`{rel}`](../../../problems/scenes/{rel}) | {cell(description)} | {cell(what)} "
      f"| `{command}` |")
PY
  echo "gallery: $rel: exit $status, ${seconds} s, picture $picture" >&2
done
[[ $ran -gt 0 ]] || { echo "gallery: no scene matches '$only'" >&2; exit 2; }

# The index: this run's rows, and the kept rows of the scenes not run (--only); pictures of
# scenes that are gone are removed.
python3 - "$out" "$tmp/rows" "${scenes[@]}" <<'PY'
import os, sys
out, rows_dir, scenes = sys.argv[1], sys.argv[2], sys.argv[3:]
index = os.path.join(out, "README.md")
old = open(index).read().splitlines() if os.path.exists(index) else []
names = {rel: rel[:-len(".json")].replace("/", "-") for rel in scenes}
rows = []
for rel in scenes:
    fresh = os.path.join(rows_dir, names[rel] + ".md")
    if os.path.exists(fresh):
        rows.append(open(fresh).read().rstrip("\n"))
    else:
        kept = [line for line in old if f"](../../../problems/scenes/{rel})" in line]
        rows.extend(kept[:1])
for file in os.listdir(out):
    if file.endswith(".png") and file[:-4] not in names.values():
        os.remove(os.path.join(out, file))
total = sum(os.path.getsize(os.path.join(out, f)) for f in os.listdir(out) if f.endswith(".png"))
pictures = sum(1 for f in os.listdir(out) if f.endswith(".png"))
with open(index, "w") as f:
    f.write(f"""# Gallery of the bundled scenes

Every scene under `problems/scenes/` at its last frame, written by `bash scripts/gallery.sh`
(`--only REGEX` for some of them). Each picture is `liedyn view` of the run in the last column,
opened in headless Chromium at 480×360 as
`out/view.html#frame=last&paused&hide=panel,ui,title`: the camera frames the whole run (every
body and rod over all frames, and the colliders of finite size), except for a few scenes whose
objects would be small in it, which fit their last frame (`&fit=frame`) and say so. To see a
run move, open `out/view.html` after `liedyn view out`.

Optimisation scenes are simulated forward at their initial parameters (`liedyn simulate`), not
optimised. A run that did not converge, failed or was shortened says so in its row; a body
without a solid or contact samples is drawn as a triad of its axes.
{pictures} pictures, {total / 1e6:.2f} MB.

| picture | scene | description | simulated | command |
| --- | --- | --- | --- | --- |
""")
    f.write("\n".join(rows) + "\n")
PY
echo "gallery: $ran scenes in $(($(date +%s) - start_all)) s; pictures and index in $out" >&2
du -cb "$out"/*.png | tail -n 1 | sed 's/total$/bytes of pictures in all/' >&2
