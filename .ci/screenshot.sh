#!/usr/bin/env bash
# Starts the release binary under Xvfb on each built-in demo device, takes a screenshot of one
# panel of each, and fails if a window did not come up or a shot is blank.
# Usage: .ci/screenshot.sh [DIR]   (default: target/screenshots)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-target/screenshots}
bin=target/release/botbench
# name  demo device  panel  seconds to let it connect, read and plot
shots=(
    "tuning window-cleaner Tuning 6"
    "telemetry window-cleaner Telemetry 6"
    "solar solar-cleanbot Solar 6"
    "servo servo-bus ServoBench 4"
    "tuya tuya-vacuum TuyaConsole 6"
)

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

# A fresh settings folder, so that nothing saved before changes what the window shows.
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
cat > "$home/run.sh" <<SCRIPT
#!/usr/bin/env bash
set -u
export HOME="$home" XDG_CONFIG_HOME="$home/config" XDG_DATA_HOME="$home/data" LIBGL_ALWAYS_SOFTWARE=1
# xvfb-run gives the server a fixed few seconds to start; on a loaded machine it needs more.
for _ in \$(seq 1 60); do
    if xdotool getdisplaygeometry >/dev/null 2>&1; then break; fi
    sleep 0.5
done
echo "X display \$DISPLAY: \$(xdotool getdisplaygeometry 2>&1)"
# Now and then the app cannot open its X connection at start, though the server answers (about
# one launch in ten under Xvfb here): each shot gets three launches.
launch() {
    "$PWD/$bin" gui --demo "\$1" --panel "\$2" > "$home/app.log" 2>&1 &
    app=\$!
    for _ in \$(seq 1 120); do
        if xdotool search --name "botbench" >/dev/null 2>&1; then return 0; fi
        if ! kill -0 \$app 2>/dev/null; then
            echo "the app exited early (\$1 \$2):"; cat "$home/app.log"; return 1
        fi
        sleep 0.5
    done
    echo "no window titled botbench after 60 s (\$1 \$2)"; cat "$home/app.log"; kill \$app; return 1
}
shot() {
    launch "\$2" "\$3" || { sleep 1; launch "\$2" "\$3"; } || { sleep 1; launch "\$2" "\$3"; } || exit 1
    sleep "\$4"
    import -window root "$dir/\$1.png"
    kill \$app
    wait \$app 2>/dev/null || true
}
SCRIPT
for s in "${shots[@]}"; do echo "shot $s" >> "$home/run.sh"; done
chmod +x "$home/run.sh"
# Two xvfb-run -a started at once can race for a display number: one retry.
xvfb-run -a -s "-screen 0 1280x800x24" "$home/run.sh" || {
    echo "== the X session failed; retrying once"
    sleep 2
    xvfb-run -a -s "-screen 0 1280x800x24" "$home/run.sh"
}

# Blank means a single colour: its standard deviation is (about) zero.
for s in "${shots[@]}"; do
    shot="$dir/${s%% *}.png"
    sd=$(/usr/bin/convert "$shot" -format "%[fx:standard_deviation]" info:)
    echo "screenshot $shot: standard deviation $sd"
    awk -v sd="$sd" 'BEGIN { exit !(sd > 0.02) }' || { echo "$shot is blank"; exit 1; }
done
