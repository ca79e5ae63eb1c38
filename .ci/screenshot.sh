#!/usr/bin/env bash
# Opens the window once under Xvfb (software rendering) for its screenshot tour (`botbench gui
# --screenshots DIR`): each built-in demo device in turn, every view it has (each panel, each
# tab, each tuning group), at 1280×800 and 1024×600, in English and 中文. Fails if the window
# did not come up, the tour reported a failure (a device that did not answer, a label split
# over two lines), a view lacks one of its four shots, or a shot is blank. Then the line
# station's window (`botbench station presets/demo-station.ron --screenshots DIR`): 8 shots.
# Usage: .ci/screenshot.sh [DIR] [BINARY]
#   DIR     default target/screenshots (emptied of old shots first)
#   BINARY  default target/debug/botbench: the one `cargo test` builds, so CI builds once
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-target/screenshots}
bin=${2:-target/debug/botbench}

need=()
for cmd in xvfb-run xauth xdotool identify; do
    command -v "$cmd" >/dev/null 2>&1 || need+=("$cmd")
done
if [ ${#need[@]} -gt 0 ] || [ ! -e /usr/lib/x86_64-linux-gnu/dri/swrast_dri.so ]; then
    echo "== installing Xvfb, ImageMagick, xdotool and Mesa (missing: ${need[*]:-mesa})"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq xvfb xauth imagemagick xdotool libegl1 libegl-mesa0 libgl1-mesa-dri libglx-mesa0 >/dev/null
    echo "== installed in $SECONDS s"
fi
[ -x "$bin" ] || cargo build
bin=$(realpath "$bin")

# A fresh settings folder, so that nothing saved before changes what the window shows.
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
rm -f "$dir"/*.png
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
# one launch in ten under Xvfb here): three launches.
for attempt in 1 2 3; do
    # Then the line station (the demo bundle, one unit per slot): a question waiting, then
    # the verdicts (the first yes/no answered no: one FAIL banner), each at both sizes in both
    # languages.
    "$bin" gui --screenshots "$dir" > "$home/app.log" 2>&1 \
        && "$bin" station "$PWD/presets/demo-station.ron" --screenshots "$dir" \
            --records "$home/station-records.sqlite" >> "$home/app.log" 2>&1 && exit 0
    grep -q "Failed to open connection to X server" "$home/app.log" || break
    echo "launch \$attempt could not open its X connection; again"
    sleep 1
done
cat "$home/app.log"
exit 1
SCRIPT
chmod +x "$home/run.sh"
# Two xvfb-run -a started at once can race for a display number: one retry.
tour_start=$SECONDS
xvfb-run -a -s "-screen 0 1280x800x24" "$home/run.sh" || {
    echo "== the X session failed; retrying once"
    sleep 2
    xvfb-run -a -s "-screen 0 1280x800x24" "$home/run.sh"
}
grep "^tour: .* shots in" "$home/app.log" || true
grep "^tour: done" "$home/app.log"
echo "== the tour took $((SECONDS - tour_start)) s (X server and launches included)"
grep "^station tour: done" "$home/app.log" || true
if ! grep -q "^station tour: done, 8 shots, 0 failures" "$home/app.log"; then
    grep "^station tour:" "$home/app.log" || echo "the station's tour did not finish"
    exit 1
fi
if ! grep -q "^tour: done, 0 failure" "$home/app.log"; then
    grep "^tour:" "$home/app.log" | grep -v "\.png$"
    exit 1
fi

# Every device's shots, and each view shown at both sizes in both languages.
for device in window-cleaner solar-cleanbot servo-bus tuya-vacuum; do
    ls "$dir/$device"-*.png >/dev/null 2>&1 || { echo "no shot of $device"; exit 1; }
done
for view in $(ls "$dir" | sed -n 's/-[0-9]*x[0-9]*-[a-z]*\.png$//p' | sort -u); do
    for shot in 1280x800-en 1280x800-zh 1024x600-en 1024x600-zh; do
        [ -s "$dir/$view-$shot.png" ] || { echo "missing $view-$shot.png"; exit 1; }
    done
done
# Blank means a single colour: its standard deviation is (about) zero.
/usr/bin/identify -format "%f %[fx:standard_deviation]\n" "$dir"/*.png | awk '
    $2 <= 0.02 { print "blank: " $1; bad = 1 }
    END { print NR " screenshots in '"$dir"'"; exit bad }'
