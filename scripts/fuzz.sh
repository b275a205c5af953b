#!/usr/bin/env bash
# Fuzzes the scene loader with libFuzzer (tests/fuzz/scene_fuzzer.cpp, docs/fuzzing.md).
#   bash scripts/fuzz.sh [SECONDS]     default 300
# Builds build-fuzz/ with clang (-DLIEDYN_FUZZ=ON), seeds build-fuzz/corpus/ with every
# problems/scenes/**/*.json (the corpus grows there across runs; the repository is not
# touched) and fuzzes for SECONDS. Exits non-zero when an input crashed, hung or ran out of
# memory, and prints where the reproducer is.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
seconds=${1:-300}
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "usage: $0 [SECONDS]  (a positive whole number of seconds, default 300)" >&2
  exit 2
fi

# Library dependencies, then clang, libFuzzer's runtime and clang's OpenMP (not in
# install-deps.sh: only fuzzing needs them).
bash "$root/scripts/install-deps.sh"
packages=(clang libclang-rt-14-dev libomp-14-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update
  "${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
fi

build="$root/build-fuzz"
# -O1 -g without -DNDEBUG: fast enough, with line numbers in reports and Eigen's asserts on.
options=(-DCMAKE_CXX_COMPILER=clang++ -DLIEDYN_FUZZ=ON
         -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g"
         -DLIEDYN_BUILD_TESTS=OFF -DLIEDYN_BUILD_BENCHMARKS=OFF)
if command -v ccache >/dev/null; then
  export CCACHE_DIR="${CCACHE_DIR:-/var/cache/liedyn-ccache}"
  mkdir -p "$CCACHE_DIR" 2>/dev/null || export CCACHE_DIR="$HOME/.cache/liedyn-ccache"
  options+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$root" -B "$build" "${options[@]}"
cmake --build "$build" --target liedyn_scene_fuzzer -j"$(nproc)"
fuzzer="$build/tests/fuzz/liedyn_scene_fuzzer"

# Seeds: the bundled scenes, flattened into one directory (letters/letter_A.json →
# letters_letter_A.json).
corpus="$build/corpus"
artifacts="$build/artifacts"
mkdir -p "$corpus" "$artifacts"
while IFS= read -r -d '' scene; do
  relative=${scene#"$root/problems/scenes/"}
  cp "$scene" "$corpus/seed_${relative//\//_}"
done < <(find "$root/problems/scenes" -name '*.json' -print0)

# -max_len: the largest bundled scene is about 10 kB. -timeout: seconds per input (a hang is a
# bug; the largest scene the parser accepts, 2·10⁶ generated rod edges, takes about 20 s in this
# instrumented build). -rss_limit_mb: also the limit of a single allocation (-malloc_limit_mb
# defaults to it).
marker="$build/.fuzz-start"
touch "$marker"
status=0
ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}" \
UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}" \
  "$fuzzer" -max_total_time="$seconds" -max_len=16384 -timeout=60 -rss_limit_mb=2048 \
    -dict="$root/tests/fuzz/scene.dict" -artifact_prefix="$artifacts/" -print_final_stats=1 \
    "$corpus" || status=$?

mapfile -t found < <(find "$artifacts" -type f -newer "$marker" | sort)
if [ "$status" -ne 0 ] || [ ${#found[@]} -gt 0 ]; then
  echo "fuzz: the fuzzer stopped with status $status; reproducer(s):" >&2
  for f in "${found[@]}"; do echo "  $f" >&2; done
  echo "fuzz: reproduce with $fuzzer <file>" >&2
  exit 1
fi
echo "fuzz: no crash in ${seconds} s; corpus $corpus ($(find "$corpus" -type f | wc -l) inputs)"
