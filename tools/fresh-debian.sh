#!/usr/bin/env bash
# Runs commands of this repository in a brand-new minimal Debian 12 system, the way a newcomer's
# machine starts (nothing but apt, git and sudo), so that an install step that lives only on the
# developers' machines or the CI host (a package installed by hand, a file left in a tree) fails
# here instead of on the user's. `.ci/run` runs the README's two commands through it.
#
#   tools/fresh-debian.sh [--keep] [--refresh] [--] COMMAND    (as root, from anywhere in the repo)
#
# COMMAND is a bash command line, run in a clone of this repository's committed HEAD inside the
# new system (uncommitted changes are not seen: commit first). Default: tools/bootstrap.sh demo.
#   --keep      keep the system afterwards (its path is printed) instead of removing it
#   --refresh   make the base system anew instead of using the cached one
# The base system is made once with mmdebstrap from this machine's own apt sources and cached as
# a tarball; each run unpacks a clean copy. Packages that apt downloads inside are kept in the
# cache too (the next run reinstalls them from there: what is tested is that the commands install
# them, not the mirror's speed). Cache: $RTWALL_FRESH_CACHE, default /var/cache/rtwall-fresh-debian.
set -euo pipefail

keep=0
refresh=0
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) keep=1; shift ;;
    --refresh) refresh=1; shift ;;
    --) shift; break ;;
    -*) echo "fresh-debian: unknown option '$1' (usage: tools/fresh-debian.sh [--keep] [--refresh] [--] COMMAND)" >&2; exit 2 ;;
    *) break ;;
  esac
done
command_line="${*:-tools/bootstrap.sh demo}"

say() { printf '[fresh-debian] %s\n' "$*"; }
[ "$(id -u)" -eq 0 ] || { echo "fresh-debian: run as root (it makes a chroot and mounts /proc, /sys and /dev into it)" >&2; exit 2; }
repo=$(git -C "$(dirname "${BASH_SOURCE[0]}")" rev-parse --show-toplevel)
cache=${RTWALL_FRESH_CACHE:-/var/cache/rtwall-fresh-debian}

# This machine's own apt sources: the new system gets its packages where this one does.
sources=/etc/apt/sources.list.d/debian.sources
[ -f "$sources" ] || sources=/etc/apt/sources.list
[ -f "$sources" ] || { echo "fresh-debian: no apt sources on this machine ($sources)" >&2; exit 1; }
# One base per set of sources, so that a machine with other mirrors never reuses a foreign base.
key=$(sha256sum "$sources" | cut -c1-12)
tarball=$cache/bookworm-minimal-$key.tar
archives=$cache/apt-archives
mkdir -p "$cache" "$archives/partial"

if [ $refresh -eq 1 ] || [ ! -s "$tarball" ]; then
  if ! command -v mmdebstrap >/dev/null; then
    say "installing mmdebstrap on this machine"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends mmdebstrap >/dev/null
  fi
  say "making a minimal Debian 12 system from $sources (cached in $tarball)"
  # The output name ends in .tar, so mmdebstrap writes a tarball (not a directory).
  mmdebstrap --quiet --variant=apt --include=ca-certificates,git,sudo bookworm "$tarball.part.tar" "$sources"
  mv "$tarball.part.tar" "$tarball"
fi

root=$(mktemp -d /var/tmp/rtwall-fresh-debian.XXXXXX)
mounted=0
cleanup() {
  local rc=$?
  trap - EXIT INT TERM
  # Everything the run mounted lies under the root, which is a mount of its own (below),
  # including what the tests mount inside (ip netns mounts /run/netns).
  if [ $mounted -eq 1 ]; then umount -R "$root" 2>/dev/null || umount -R -l "$root" 2>/dev/null || true; fi
  if [ $keep -eq 1 ]; then
    say "kept the system in $root (unmounted)"
  elif grep -q " $root" /proc/mounts; then
    # Never delete through a mount that is still there: it could be this machine's /dev.
    say "not removing $root: something is still mounted under it" >&2
  else
    rm -rf --one-file-system "$root"
  fi
  exit $rc
}
trap cleanup EXIT INT TERM
bind() {  # bind HOST_PATH PATH_IN_ROOT
  mkdir -p "$root$2"
  mount --rbind "$1" "$root$2"
  mount --make-rslave "$root$2"
}

# The root is a mount point of its own, private to this run, as / is on a real machine:
# `ip netns add` remounts / (mount --make-rslave /) and fails where / is a plain directory.
mount --bind "$root" "$root"
mount --make-private "$root"
mounted=1
tar -xf "$tarball" -C "$root"
cp /etc/resolv.conf "$root/etc/resolv.conf" 2>/dev/null || true
mount -t proc proc "$root/proc"
bind /sys /sys
bind /dev /dev
bind "$archives" /var/cache/apt/archives
# Keep what apt downloads (some minimal images delete it after every install).
rm -f "$root/etc/apt/apt.conf.d/docker-clean"
echo 'Binary::apt::APT::Keep-Downloaded-Packages "true";' >"$root/etc/apt/apt.conf.d/90rtwall-keep-archives"

git clone -q "$repo" "$root/srv/rtwall"
say "in a new Debian 12 system ($(cat "$root/etc/debian_version")), at $(git -C "$repo" rev-parse --short HEAD): $command_line"
start=$(date +%s)
set +e
chroot "$root" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  LANG=C.UTF-8 TERM=dumb /bin/bash -c "cd /srv/rtwall && $command_line"
rc=$?
set -e
say "exit status $rc after $(( $(date +%s) - start )) s"
# Inputs a fuzz run found (crashes, timeouts) are written inside the system, which goes next:
# they come out into this repository's tests/fuzz/crashes/, to be kept as regression files.
found=$(cd "$root/srv/rtwall" && git status --porcelain --untracked-files=all -- tests/fuzz/crashes | sed -n 's/^?? //p')
if [ -n "$found" ]; then
  while IFS= read -r f; do
    mkdir -p "$repo/$(dirname "$f")"
    cp "$root/srv/rtwall/$f" "$repo/$f"
    say "fuzz input found inside, kept as $repo/$f"
  done <<<"$found"
fi
exit $rc
