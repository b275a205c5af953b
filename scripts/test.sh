#!/usr/bin/env bash
# Installs what is missing, configures, builds and runs every test.
#   bash scripts/test.sh              Release build in build/
#   bash scripts/test.sh --sanitize   AddressSanitizer + UBSan build in build-asan/
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install-deps.sh"

build="$root/build"
# The test suite's sources in batches of 8 (LIEDYN_UNITY_TESTS, tests/CMakeLists.txt); the
# libraries, whose speed the README's figures are, file by file.
options=(-DCMAKE_BUILD_TYPE=Release -DLIEDYN_UNITY_TESTS=ON -DCMAKE_UNITY_BUILD=OFF)
ctest_options=()
if [ "${1:-}" = "--sanitize" ]; then
  build="$root/build-asan"
  # -O1 -g1 rather than RelWithDebInfo's -O2 -g: half the compile time (97 → 46 s for
  # test_rod_validation.cpp), which is most of this phase in CI; -g1 keeps the line tables
  # that sanitizer reports print.
  # Every target in batches of 8 here (CMAKE_UNITY_BUILD), where speed is not measured.
  options=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
           -DLIEDYN_SANITIZE=ON -DLIEDYN_BUILD_BENCHMARKS=OFF -DCMAKE_UNITY_BUILD=ON)
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp:print_suppressions=0"
  # Every test runs ~15× slower here. Left out, as they repeat for minutes what the rest of the
  # suite runs under the sanitizers already: the arm's two L-BFGS runs to their target (~1000
  # iterations, 300 s; its gradcheck stays), the gradcheck of every joint type's scene (100 s;
  # the joint terms' adjoint blocks have their own tests), every joint scene under the nine
  # back-end and parameterisation pairs (235 s; JointsChain.BackEndsAndParameterisationsAgree
  # runs the three back-ends and parameterisations on joints here), the endoscope's and the coiled rope's whole runs
  # (110 and 75 s; ContactSearch.* runs both scenes' contact search, and the rod-contact terms
  # have their own tests) and the downstream project's install and build (packaging, checked
  # by the Release run).
  ctest_options+=(-E '^(JointsCli[.](TheArmReachesItsTargetWithNloptAndIpopt|GradcheckPassesThroughEveryJointTypeElasticAndExact|EveryJointSceneRunsUnderEveryBackEndAndParameterisation)|RodContactScenes[.](TheEndoscopeRidesOverThePolyp|TheCoiledRopeLiesOnItselfAndWithoutSelfContactPassesThrough)|downstream_find_package)$')
fi
# ccache (outside the clone) makes repeated CI runs on the same machine cheap.
if command -v ccache >/dev/null; then
  export CCACHE_DIR="${CCACHE_DIR:-/var/cache/liedyn-ccache}"
  mkdir -p "$CCACHE_DIR" 2>/dev/null || export CCACHE_DIR="$HOME/.cache/liedyn-ccache"
  # Paths below the clone are hashed relative to it, so a fresh clone elsewhere still hits.
  export CCACHE_BASEDIR="$root"
  options+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# Ninja compiles a target's sources before the libraries it links are archived (Make goes
# target by target), the test suite's too (it needs the CLI only to link, tests/CMakeLists.txt).
# An existing build folder keeps its generator.
[ -f "$build/CMakeCache.txt" ] || options+=(-G Ninja)
jobs=$(nproc)
cmake -S "$root" -B "$build" "${options[@]}"
cmake --build "$build" -j"$jobs"
ctest --test-dir "$build" --output-on-failure -j"$jobs" "${ctest_options[@]}"
