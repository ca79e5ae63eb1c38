#!/usr/bin/env bash
# Starts the release binary under Xvfb on its built-in demo device, takes a screenshot, and
# fails if the window did not come up or the shot is blank.
# Usage: .ci/screenshot.sh [OUT.png]   (default: target/screenshot.png; a second shot of the
# telemetry panel goes beside it as OUT-telemetry.png)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-target/screenshot.png}
out2=${out%.png}-telemetry.png
bin=target/release/botbench

need=()
for cmd in xvfb-run xauth import xdotool; do
    command -v "$cmd" >/dev/null 2>&1 || need+=("$cmd")
done
if [ ${#need[@]} -gt 0 ] || [ ! -e /usr/lib/x86_64-linux-gnu/dri/swrast_dri.so ]; then
    echo "== installing Xvfb, ImageMagick, xdotool and Mesa (missing: ${need[*]:-mesa})"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq xvfb xauth imagemagick xdotool libegl1 libegl-mesa0 libgl1-mesa-dri libglx-mesa0 >/dev/null
fi
[ -x "$bin" ] || cargo build --release

# A fresh settings folder, so the window opens on the demo device whatever was saved before.
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
cat > "$home/run.sh" <<SCRIPT
#!/usr/bin/env bash
set -u
export HOME="$home" XDG_CONFIG_HOME="$home/config" XDG_DATA_HOME="$home/data" LIBGL_ALWAYS_SOFTWARE=1
"$PWD/$bin" > "$home/app.log" 2>&1 &
app=\$!
for _ in \$(seq 1 120); do
    if xdotool search --name "botbench" >/dev/null 2>&1; then break; fi
    if ! kill -0 \$app 2>/dev/null; then echo "the app exited early:"; cat "$home/app.log"; exit 1; fi
    sleep 0.5
done
if ! xdotool search --name "botbench" >/dev/null 2>&1; then
    echo "no window titled botbench after 60 s"; cat "$home/app.log"; kill \$app; exit 1
fi
# Let it connect to the demo device, read and plot for a moment.
sleep 6
import -window root "$PWD/$out"
# The telemetry panel: second in the navigation on the left.
xdotool mousemove 45 64 click 1
sleep 5
import -window root "$PWD/$out2"
kill \$app
wait \$app 2>/dev/null || true
SCRIPT
chmod +x "$home/run.sh"
mkdir -p "$(dirname "$out")"
xvfb-run -a -s "-screen 0 1280x800x24" "$home/run.sh"

# Blank means a single colour: its standard deviation is (about) zero.
for shot in "$out" "$out2"; do
    sd=$(/usr/bin/convert "$shot" -format "%[fx:standard_deviation]" info:)
    echo "screenshot $shot: standard deviation $sd"
    awk -v sd="$sd" 'BEGIN { exit !(sd > 0.02) }' || { echo "$shot is blank"; exit 1; }
done
