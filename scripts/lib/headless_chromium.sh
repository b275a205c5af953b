# Headless Chromium for the page checks (scripts/viewer/check_view.sh,
# scripts/export/check_glb.sh); source it.
#
#   chromium_path                     prints Chromium's path; fails when it is not installed
#   run_headless_chromium TOOL LOG ARG…
#       runs Chromium on the page (ARG…: its flags and URL) with a fresh profile (no lock held
#       by another Chromium, nothing left in ~/.config), --no-sandbox (we run as root) and the
#       console on stderr (each message as [...:CONSOLE(LINE)] "MESSAGE", source: URL) into
#       LOG; sets chromium_status to its exit status and prints "TOOL: chromium took …"
#   page_console LOG                  prints the page's console messages from LOG

chromium_path() {
  command -v chromium || command -v chromium-browser
}

run_headless_chromium() {
  local tool=$1 log=$2
  shift 2
  local chrome profile start ms
  chrome=$(chromium_path) || return 1
  profile=$(mktemp -d)
  start=$(date +%s%N)
  chromium_status=0
  timeout 300 "$chrome" --headless --no-sandbox --disable-gpu --user-data-dir="$profile" \
    --enable-logging=stderr --v=0 "$@" >"$log.out" 2>"$log" || chromium_status=$?
  ms=$((($(date +%s%N) - start) / 1000000))
  rm -rf "$profile"
  printf '%s: chromium took %d.%03d s (exit status %d)\n' "$tool" $((ms / 1000)) $((ms % 1000)) "$chromium_status"
}

page_console() {
  grep -E '^\[[^]]*:CONSOLE[:(]' "$1" || true
}
