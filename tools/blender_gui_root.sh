#!/usr/bin/env bash
# Blender in a real window on a machine that has none (make test-gui, tests/farm).
#
# Builds a Debian 13 ("trixie") root with debootstrap, from the Debian mirror this machine's
# apt already uses, holding Debian's own Blender (a GUI build with its system Python and
# numpy), Xvfb, ImageMagick, xdotool and x11-utils, and runs Blender in it on a virtual
# screen. Needs root (debootstrap, chroot, mount).
#
#   tools/blender_gui_root.sh setup
#       build the root if it is missing (about 2 minutes and 1 GB), then bind-mount the
#       host's /proc, /dev, /dev/shm and /dev/pts into it (Blender and Xvfb need them; they stay
#       mounted so tests/farm/test_real_blender.py can run Blender there too)
#   tools/blender_gui_root.sh run ZIP SCRIPT OUTDIR [WxH]
#       install the extension ZIP for a throw-away HOME, start Xvfb (default 1920x1200),
#       run `blender --python SCRIPT` on it; the files SCRIPT writes into $SHOTS are copied
#       to OUTDIR with blender.log and install.log. Exit status: Blender's (3: install failed).
#   tools/blender_gui_root.sh shell      a shell in the root
#   tools/blender_gui_root.sh unmount    undo the bind mounts
#
# BLENDER_GUI_ROOT (default /opt/blender-gui-root) is where the root lives;
# BLENDER_GUI_TIMEOUT (s, default 300) bounds the Blender run.
#
# A SCRIPT works from bpy.app.timers callbacks (the window exists only once the event loop
# runs), takes pictures with ImageMagick (`import -window root $SHOTS/x.png`: Blender's own
# screenshot operator gives black images on software OpenGL), clicks and types with xdotool,
# and ends with bpy.ops.wm.quit_blender().
set -euo pipefail

root=${BLENDER_GUI_ROOT:-/opt/blender-gui-root}
suite=trixie
packages="blender python3-numpy xvfb xauth libgl1-mesa-dri imagemagick xdotool x11-utils"

die() { echo "blender_gui_root: $*" >&2; exit 1; }

# The first Debian archive named in apt's sources (one-line .list files and deb822 .sources
# files alike), skipping the security archive, which has no trixie main suite of its own.
debian_mirror() {
    local files=(/etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources)
    local f
    for f in "${files[@]}"; do
        [ -f "$f" ] || continue
        awk '
            /^[[:space:]]*#/ { next }
            $1 == "deb" { for (i = 2; i <= NF; i++) if ($i ~ /^https?:\/\//) { print $i; break } }
            $1 == "URIs:" { for (i = 2; i <= NF; i++) print $i }
        ' "$f"
    done | grep -E '^https?://.*/debian/?$' | head -n 1
}

is_mounted() { awk -v p="$root/$1" '$2 == p { found = 1 } END { exit !found }' /proc/mounts; }

mount_binds() {
    local d
    for d in proc dev dev/shm dev/pts; do
        mkdir -p "$root/$d"
        is_mounted "$d" || mount --bind "/$d" "$root/$d"
    done
}

unmount_binds() {
    local d
    for d in dev/pts dev/shm dev proc; do
        if is_mounted "$d"; then umount "$root/$d"; fi
    done
}

ready() { [ -x "$root/usr/bin/blender" ] && [ -x "$root/usr/bin/Xvfb" ] && [ -x "$root/usr/bin/xdotool" ]; }

setup() {
    [ "$(id -u)" -eq 0 ] || die "needs root (debootstrap, chroot and mount)"
    if ! ready; then
        command -v debootstrap >/dev/null || {
            echo "installing debootstrap"
            apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null
        }
        local mirror
        mirror=$(debian_mirror) || true
        [ -n "$mirror" ] || die "no Debian archive in /etc/apt/sources.list*: cannot choose a mirror"
        mkdir -p "$(dirname "$root")"
        if [ ! -x "$root/usr/bin/apt-get" ]; then
            echo "debootstrap $suite into $root from $mirror"
            debootstrap --variant=minbase "$suite" "$root" "$mirror" >"$root.debootstrap.log" 2>&1 \
                || die "debootstrap failed, see $root.debootstrap.log"
            rm -f "$root.debootstrap.log"
        fi
        mount_binds
        echo "installing $packages"
        chroot "$root" /usr/bin/env DEBIAN_FRONTEND=noninteractive bash -c \
            "apt-get update -qq && apt-get install -y -qq --no-install-recommends $packages >/dev/null" \
            || die "apt-get install in $root failed"
        chroot "$root" apt-get clean
    fi
    mount_binds
    # Blender asks for the mounted file systems (its file browser's list of volumes).
    [ -e "$root/etc/mtab" ] || ln -s /proc/self/mounts "$root/etc/mtab"
    echo "ready: $root, $(chroot "$root" blender --version 2>/dev/null | head -n 1)"
}

run() {
    [ $# -ge 3 ] || die "usage: $0 run ZIP SCRIPT OUTDIR [WxH]"
    local zip=$1 script=$2 outdir=$3 size=${4:-1920x1200}
    [ -f "$zip" ] || die "no extension zip at $zip"
    [ -f "$script" ] || die "no script at $script"
    setup >/dev/null
    # The job's folder, /tmp/sh-gui-job-PID as Blender sees it inside the root.
    local job=/tmp/sh-gui-job-$$
    local host=$root$job
    rm -rf "$host"
    mkdir -p "$host/home" "$host/shots" "$outdir"
    cp "$zip" "$host/extension.zip"
    cp "$script" "$host/script.py"
    local status=0
    # The script's own settings (SH_GUI_*) pass into the root; nothing else of this shell does.
    local passed=()
    mapfile -t passed < <(env | grep -E '^SH_GUI_[A-Z_]+=' || true)
    chroot "$root" /usr/bin/env -i PATH=/usr/bin:/bin HOME="$job/home" LANG=C.UTF-8 \
        "${passed[@]}" JOB="$job" SIZE="$size" LIMIT="${BLENDER_GUI_TIMEOUT:-300}" bash -c '
        blender -b --command extension install-file -r user_default -e "$JOB/extension.zip" \
            >"$JOB/install.log" 2>&1 || { cat "$JOB/install.log" >&2; exit 3; }
        # Xvfb picks a free display itself and writes its number to fd 3.
        Xvfb -displayfd 3 -screen 0 "${SIZE}x24" -nolisten tcp 3>"$JOB/display" \
            >"$JOB/xvfb.log" 2>&1 &
        xvfb=$!
        for _ in $(seq 100); do [ -s "$JOB/display" ] && break; sleep 0.1; done
        [ -s "$JOB/display" ] || { echo "Xvfb did not start:" >&2; cat "$JOB/xvfb.log" >&2; exit 4; }
        DISPLAY=":$(cat "$JOB/display")" SHOTS="$JOB/shots" timeout "$LIMIT" \
            blender --python "$JOB/script.py" >"$JOB/blender.log" 2>&1
        code=$?
        kill "$xvfb" 2>/dev/null; wait "$xvfb" 2>/dev/null
        exit "$code"' || status=$?
    cp -r "$host/shots/." "$outdir/"
    local f
    for f in blender.log install.log; do
        if [ -f "$host/$f" ]; then cp "$host/$f" "$outdir/"; fi
    done
    rm -rf "$host"
    return "$status"
}

case "${1:-}" in
    setup) setup ;;
    run) shift; run "$@" ;;
    shell) setup >/dev/null; chroot "$root" bash ;;
    unmount) unmount_binds ;;
    *) sed -n '2,27p' "$0" | sed -E 's/^# ?//'; exit 2 ;;
esac
