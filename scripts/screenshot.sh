#!/usr/bin/env bash
# A screenshot of the real workbench window, under Xvfb with Mesa's software OpenGL.
#
# Installs nothing itself. On Debian/Ubuntu:
#   apt-get install -y xvfb libgl1-mesa-dri imagemagick
#
# Usage: scripts/screenshot.sh [OUT.png] [-- APP ARGS...]
#   default: assets/screenshot.png of the default scene with a probe, the reference
#   and the gradient overlay. The app writes a "ready" file once the field has
#   converged and everything asked for is computed; the shot is taken then.
#   The app's output goes to $SCREENSHOT_LOG (default /tmp/volcache_screenshot.log);
#   with VOLCACHE_FRAME_TIME=1 it includes the frame times.
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-assets/screenshot.png}
shift || true
[[ ${1:-} == "--" ]] && shift
app_args=("$@")
if [[ ${#app_args[@]} -eq 0 ]]; then
    app_args=(app --probe 0.12,-0.32 --reference --gradients --false-color)
fi

for tool in Xvfb import; do
    command -v "$tool" >/dev/null || {
        echo "missing $tool: apt-get install -y xvfb libgl1-mesa-dri imagemagick" >&2
        exit 1
    }
done

cargo build --release --quiet
display=:${SCREENSHOT_DISPLAY:-99}
ready=$(mktemp -u /tmp/volcache_ready.XXXXXX)
log=${SCREENSHOT_LOG:-/tmp/volcache_screenshot.log}

Xvfb "$display" -screen 0 1280x800x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
app=
cleanup() {
    [[ -n $app ]] && kill "$app" 2>/dev/null || true
    kill "$xvfb" 2>/dev/null || true
    rm -f "$ready"
}
trap cleanup EXIT
for _ in $(seq 50); do
    [[ -e /tmp/.X11-unix/X${display#:} ]] && break
    sleep 0.1
done

DISPLAY=$display LIBGL_ALWAYS_SOFTWARE=1 ./target/release/volcache "${app_args[@]}" --ready-file "$ready" \
    >"$log" 2>&1 &
app=$!

timeout=${WAIT_SECONDS:-300}
for _ in $(seq $((timeout * 10))); do
    [[ -e $ready ]] && break
    kill -0 "$app" 2>/dev/null || { echo "the app exited early:" >&2; cat "$log" >&2; exit 1; }
    sleep 0.1
done
[[ -e $ready ]] || { echo "not converged after ${timeout}s" >&2; exit 1; }
sleep 1 # let the last frame reach the screen
mkdir -p "$(dirname "$out")"
import -display "$display" -window root "$out"
echo "wrote $out (app log: $log)"
