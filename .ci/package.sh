#!/usr/bin/env bash
# The Debian package (issue 18): builds it from the binary already built (release, or the
# tests' debug binary with BOTBENCH_DEB_FROM=target/debug/botbench; cargo deb --no-build;
# installs cargo-deb first if it is missing, about 2 minutes on 2 cores), installs it
# with dpkg (CI runs as root), and checks the installed /usr/bin/botbench the way a line PC runs
# it: no Rust toolchain on PATH, no source checkout in reach (an empty folder, a fresh HOME):
# --version, profiles, a shipped preset found by its relative path, and the window opened on
# the demo device by the desktop entry's Exec under Xvfb (Xvfb, xdotool, ImageMagick and Mesa
# are installed by .ci/screenshot.sh, which runs first; the package itself pulls in Mesa).
set -euo pipefail
cd "$(dirname "$0")/.."
step() { echo "== $1 ($((SECONDS - t0)) s)"; }
t0=$SECONDS

if ! command -v cargo-deb >/dev/null 2>&1; then
    step "installing cargo-deb"
    cargo install cargo-deb --locked --version 3.8.0
fi
rm -f target/debian/botbench_*.deb
# The shell completions and the manual page, written by the binary that is packaged (Cargo.toml's
# [package.metadata.deb] assets install them from target/deb-assets/).
packaged=${BOTBENCH_DEB_FROM:-target/release/botbench}
[ -x "$packaged" ] || cargo build --release
step "completions and the manual page ($packaged)"
mkdir -p target/deb-assets
"$packaged" completions bash > target/deb-assets/botbench.bash
"$packaged" completions zsh > target/deb-assets/_botbench
"$packaged" completions fish > target/deb-assets/botbench.fish
"$packaged" manpage | gzip -9n > target/deb-assets/botbench.1.gz
if [ -n "${BOTBENCH_DEB_FROM:-}" ]; then
    # CI packages the debug binary its tests ran (one build). cargo-deb takes no dev profile (3.8
    # warns, later versions refuse), so the binary goes where the `ci` profile puts its own:
    # Cargo.toml's [profile.ci] is the dev profile by another name, and `cargo build --profile
    # ci` would build the same thing there. Stripped and quickly compressed: this package is
    # checked, not shipped (without either, cargo deb spends about 50 s on xz).
    step "cargo deb --no-build --profile ci --strip --fast ($BOTBENCH_DEB_FROM)"
    mkdir -p target/ci
    ln -f "$BOTBENCH_DEB_FROM" target/ci/botbench
    cargo deb --no-build --profile ci --strip --fast
else
    # The release package a line PC installs.
    [ -x target/release/botbench ] || cargo build --release
    step "cargo deb --no-build"
    cargo deb --no-build
fi
deb=$(ls target/debian/botbench_*.deb)
echo "$deb: $(du -k "$deb" | cut -f1) KiB"
dpkg-deb --contents "$deb" | awk '{ print $6 }'

step "dpkg -i"
# The libraries it names (X11, EGL, Mesa) are there after .ci/screenshot.sh; if not, apt brings
# them, as `apt install ./botbench_….deb` does on a line PC.
dpkg -i "$deb" || {
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -f -y -qq >/dev/null
}
dpkg-query -W -f='${Status} ${Version}\n' botbench | grep -q '^install ok installed '
test "$(command -v botbench)" = /usr/bin/botbench || test -x /usr/bin/botbench

# The installed app, as a line PC runs it.
home=$(mktemp -d)
trap 'kill $sim 2>/dev/null || true; rm -rf "$home"' EXIT
sim=
root=$PWD
cd "$home"
run() { env -i PATH=/usr/bin:/bin HOME="$home" LANG=C.UTF-8 "$@"; }

step "botbench --version"
version=$(run botbench --version)
echo "$version"
echo "$version" | grep -Eq '^botbench [0-9]+\.[0-9]+\.[0-9]+ \(([0-9a-f]{7,}|unknown)\)$'

step "the completions and the manual page installed"
test -s /usr/share/bash-completion/completions/botbench
test -s /usr/share/zsh/vendor-completions/_botbench
test -s /usr/share/fish/vendor_completions.d/botbench.fish
zcat /usr/share/man/man1/botbench.1.gz | grep -q '^\.TH botbench'

step "botbench profiles"
run botbench profiles | tee profiles.txt
grep -q '^window-cleaner ' profiles.txt

step "a shipped preset, by its relative path, against the simulated window cleaner"
# Not through run(): a function in the background is a subshell, and $! would name it, not the
# simulator, which `kill $sim` then left running.
env -i PATH=/usr/bin:/bin HOME="$home" LANG=C.UTF-8 botbench sim window-cleaner > sim.txt 2>&1 &
sim=$!
for _ in $(seq 1 100); do [ -s sim.txt ] && break; sleep 0.1; done
port=$(head -1 sim.txt)
set +e
run botbench preset diff presets/window-cleaner-factory.ron --port "$port" > diff.txt 2>&1
code=$?
set -e
cat diff.txt
# 0: the device holds the preset; 1: it differs. 2 would be a file not found or refused.
[ "$code" -le 1 ] || { echo "preset diff failed with exit $code"; exit 1; }
kill $sim; wait $sim 2>/dev/null || true; sim=

step "the window from the desktop entry, under Xvfb"
if ! command -v xvfb-run >/dev/null || ! command -v xdotool >/dev/null || [ ! -x /usr/bin/convert ]; then
    echo "== installing Xvfb, xdotool and ImageMagick (when run without .ci/screenshot.sh first)"
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq xvfb xauth imagemagick xdotool >/dev/null
fi
if command -v desktop-file-validate >/dev/null; then
    desktop-file-validate /usr/share/applications/botbench.desktop
fi
exec_line=$(sed -n 's/^Exec=//p' /usr/share/applications/botbench.desktop)
exe=$(PATH=/usr/bin:/bin command -v "${exec_line%% *}")
[ "$exe" = /usr/bin/botbench ] || { echo "the desktop entry runs $exe"; exit 1; }
cat > window.sh <<SCRIPT
#!/usr/bin/env bash
set -u
for _ in \$(seq 1 60); do xdotool getdisplaygeometry >/dev/null 2>&1 && break; sleep 0.5; done
# Now and then the app cannot open its X connection at start under Xvfb: three launches.
for attempt in 1 2 3; do
    env -i PATH=/usr/bin:/bin HOME="$home" DISPLAY="\$DISPLAY" XAUTHORITY="\${XAUTHORITY:-}" \
        LIBGL_ALWAYS_SOFTWARE=1 $exe ${exec_line#* } > app.log 2>&1 &
    app=\$!
    for _ in \$(seq 1 120); do
        win=\$(xdotool search --name '^botbench [0-9]' 2>/dev/null | head -1)
        if [ -n "\$win" ]; then
            echo "window: \$(xdotool getwindowname "\$win")"
            sleep 4
            import -window root window.png
            kill \$app; wait \$app 2>/dev/null
            exit 0
        fi
        kill -0 \$app 2>/dev/null || break
        sleep 0.5
    done
    echo "launch \$attempt: no window"; cat app.log; kill \$app 2>/dev/null; sleep 1
done
exit 1
SCRIPT
chmod +x window.sh
xvfb-run -a -s "-screen 0 1280x800x24" ./window.sh || {
    echo "== the X session failed; retrying once"; sleep 2
    xvfb-run -a -s "-screen 0 1280x800x24" ./window.sh
}
sd=$(/usr/bin/convert window.png -format "%[fx:standard_deviation]" info:)
echo "window screenshot: standard deviation $sd"
awk -v sd="$sd" 'BEGIN { exit !(sd > 0.02) }' || { echo "the window is blank"; exit 1; }
mkdir -p "$root/target/screenshots"
cp window.png "$root/target/screenshots/installed.png"
step "package checked"
