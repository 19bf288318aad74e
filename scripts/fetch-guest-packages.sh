#!/usr/bin/env bash
# Downloads the Debian packages of scripts/guest-packages.txt (and what the kernel meta-package
# points to) into DIR, once: a second run finds them there. Nothing is installed on the host.
# Usage: fetch-guest-packages.sh DIR
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:?usage: fetch-guest-packages.sh DIR}
mkdir -p "$dir"
want=()
while read -r pkg; do
  pkg=${pkg%%#*}
  pkg=$(echo "$pkg" | tr -d '[:space:]')
  [ -n "$pkg" ] || continue
  want+=("$pkg")
  # A meta-package (linux-image-amd64): the versioned package it depends on holds the files.
  for dep in $(apt-cache depends "$pkg" 2>/dev/null | awk '/Depends: linux-image-/ {print $2}'); do
    want+=("$dep")
  done
done < scripts/guest-packages.txt
missing=()
for pkg in "${want[@]}"; do
  ls "$dir/${pkg}_"*.deb >/dev/null 2>&1 || missing+=("$pkg")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "guest: downloading ${missing[*]} into $dir"
(cd "$dir" && apt-get download -qq "${missing[@]}") || {
  echo "guest: apt-get download failed (run 'apt-get update' first?)" >&2
  exit 1
}
