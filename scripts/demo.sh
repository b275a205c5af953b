#!/usr/bin/env bash
# Installs what is missing, builds liedyn (Release) and simulates the bundled default scene,
# the butterfly bolt (paper Fig. 4), then writes its view.html (open it in a browser). Outputs
# go to out/butterfly_bolt/ (or the folder given).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install-deps.sh"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release
cmake --build "$root/build" -j"$(nproc)" --target liedyn_cli
out="${1:-$root/out/butterfly_bolt}"
"$root/build/liedyn" simulate "$root/problems/scenes/butterfly_bolt.json" --out "$out"
"$root/build/liedyn" view "$out"
