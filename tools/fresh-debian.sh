#!/usr/bin/env bash
# Runs the README's "Try it" commands on a brand-new Debian 12 system: builds a minimal root with
# debootstrap, clones the committed HEAD of a checkout into it and runs each command the README
# shows, in a chroot, as root. Proves that the set-up installs everything the commands use.
#
#   sudo bash tools/fresh-debian.sh [CHECKOUT] [--dir DIR] [--keep] [--mirror URL]
#
# CHECKOUT: a git checkout (default: the one this script is in); its HEAD commit is cloned, not
# its working tree. DIR: where the root goes (default: a new folder under /var/tmp), removed at
# the end unless --keep. Needs root, debootstrap (installed if missing) and the network.
#
# The machine's package-index settings are carried in: the environment passes through, and the
# certificate files that SSL_CERT_FILE, PIP_CERT and REQUESTS_CA_BUNDLE name (and the folder
# SSL_CERT_DIR names) are bind-mounted read-only at the same paths, as is the PIP_FIND_LINKS
# folder. /proc, /dev and /dev/pts are mounted for the simulated Uno's pty.
# Exit status 0 when every command passed; a summary with each command's duration at the end.
set -euo pipefail

SRC="" DIR="" KEEP=0 MIRROR=http://deb.debian.org/debian
while [ $# -gt 0 ]; do
  case "$1" in
    --dir) DIR=$2; shift 2 ;;
    --keep) KEEP=1; shift ;;
    --mirror) MIRROR=$2; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) SRC=$1; shift ;;
  esac
done
SRC=$(cd "${SRC:-$(dirname "$0")/..}" && git rev-parse --show-toplevel)
SHA=$(git -C "$SRC" rev-parse HEAD)
[ "$(id -u)" -eq 0 ] || { echo "fresh-debian: must run as root (debootstrap, chroot, mount)" >&2; exit 1; }
command -v debootstrap >/dev/null || apt-get install -y -qq debootstrap >/dev/null
DIR=${DIR:-$(mktemp -d /var/tmp/hubwire-fresh.XXXXXX)}
DIR=$(realpath -m "$DIR")

say() { echo "fresh-debian: $*"; }
mounts=()
cleanup() {
  local i
  for ((i=${#mounts[@]}-1; i>=0; i--)); do umount -l "${mounts[$i]}" 2>/dev/null || true; done
  if [ "$KEEP" = 0 ]; then rm -rf --one-file-system "$DIR"; else say "root kept in $DIR"; fi
}
trap cleanup EXIT

# bind SOURCE (file or folder) at the same path inside the root, read-only
bind_ro() {
  local p=$1 t="$DIR$1"
  [ -e "$p" ] || return 0
  if [ -d "$p" ]; then mkdir -p "$t"; else mkdir -p "$(dirname "$t")"; [ -e "$t" ] || : >"$t"; fi
  mount --bind "$p" "$t" && mounts+=("$t")
  mount -o remount,bind,ro "$t"
}

start=$SECONDS
say "debootstrap bookworm (minbase) into $DIR"
# ca-certificates is there before the certificate folder is mounted over it, so that nothing
# inside the root ever writes to the machine's own folder (the mount is read-only anyway)
debootstrap --variant=minbase --include=ca-certificates bookworm "$DIR" "$MIRROR" >"$DIR.debootstrap.log" 2>&1 \
  || { tail -20 "$DIR.debootstrap.log" >&2; exit 1; }
rm -f "$DIR.debootstrap.log"
say "root ready in $((SECONDS - start)) s"

mount -t proc proc "$DIR/proc" && mounts+=("$DIR/proc")
mount --bind /dev "$DIR/dev" && mounts+=("$DIR/dev")
mount --bind /dev/pts "$DIR/dev/pts" && mounts+=("$DIR/dev/pts")
cp -L /etc/resolv.conf "$DIR/etc/resolv.conf"
# debootstrap writes no /etc/hosts (the Debian installer and Raspberry Pi OS do): without it
# "localhost" does not resolve, which no user's machine lacks
[ -s "$DIR/etc/hosts" ] || printf '127.0.0.1\tlocalhost\n::1\t\tlocalhost ip6-localhost ip6-loopback\n' >"$DIR/etc/hosts"
[ -z "${SSL_CERT_DIR:-}" ] || bind_ro "$SSL_CERT_DIR"
for v in SSL_CERT_FILE PIP_CERT REQUESTS_CA_BUNDLE PIP_FIND_LINKS; do
  p=${!v:-}
  [ -n "$p" ] && [ -e "$p" ] || continue
  mountpoint -q "$DIR$p" 2>/dev/null && continue
  # a file inside an already mounted folder is there already
  [ -n "${SSL_CERT_DIR:-}" ] && [ "$(dirname "$p")" = "$SSL_CERT_DIR" ] && continue
  bind_ro "$p"
done

# the clone: the committed HEAD, as a user would get it, in root's home (mode 0700 as on any
# Debian system: user nobody cannot read it, which the tests must not depend on)
WORK=/root/hubwire
chmod 700 "$DIR/root"
git init -q "$DIR$WORK"
git -C "$DIR$WORK" fetch -q "$SRC" "$SHA"
git -C "$DIR$WORK" checkout -q --detach FETCH_HEAD
say "cloned $SHA into $WORK"

# the README's commands: the indented lines of its "Try it" section, minus comments
mapfile -t CMDS < <(awk '/^## /{on=/^## Try it/} on && /^    [^ #]/{sub(/^    /,""); sub(/[ ]+#.*$/,""); print}' \
  "$DIR$WORK/README.md")
[ ${#CMDS[@]} -gt 0 ] || { echo "fresh-debian: no commands found in the README's Try it section" >&2; exit 1; }

status=0
summary=()
for c in "${CMDS[@]}"; do
  say "\$ $c"
  t0=$SECONDS
  if chroot "$DIR" /usr/bin/env HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
      TERM=dumb /bin/bash -c "cd $WORK && $c" </dev/null; then
    summary+=("PASS $((SECONDS - t0)) s  $c")
  else
    summary+=("FAIL $((SECONDS - t0)) s  $c")
    status=1
    break
  fi
done
say "summary (commit $SHA, $((SECONDS - start)) s in all):"
for s in "${summary[@]}"; do say "  $s"; done
exit $status
