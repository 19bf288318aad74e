#!/usr/bin/env bash
# Installs what canemu needs, idempotently:
#   - the Debian packages listed in scripts/apt-packages.txt and scripts/apt-packages-guest.txt
#     (qemu for the guest test), or in the lists given as arguments (through sudo when not root);
#   - Python virtual environments: .venv (pinned PyPI packages from requirements.txt) and
#     .venv-debian (Debian's python3-can), each with canemu's python-can interface.
# A second run finds nothing to do and says so.
set -euo pipefail
cd "$(dirname "$0")/.."

lists=("$@")
[ ${#lists[@]} -gt 0 ] || lists=(scripts/apt-packages.txt scripts/apt-packages-guest.txt)
missing=()
for list in "${lists[@]}"; do
  while read -r pkg; do
    pkg=${pkg%%#*}
    pkg=$(echo "$pkg" | tr -d '[:space:]')
    [ -n "$pkg" ] || continue
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed'; then
      missing+=("$pkg")
    fi
  done < "$list"
done

did_something=0
if [ ${#missing[@]} -gt 0 ]; then
  echo "deps: installing Debian packages: ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "deps: need root or sudo to install ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
  did_something=1
fi

# Debian's interpreter, not whatever python3 is first on PATH, so the venv is the same everywhere.
# .venv: PyPI's pinned packages (requirements.txt) and canemu's python-can interface, editable.
# .venv-debian: Debian's python3-can (4.1) and pytest, with the same interface on top, and the
#   LDF import's packages (requirements-lin.txt) and the DBC import's (requirements-dbc.txt, without
#   dependencies: cantools would replace Debian's python-can with PyPI's).
py=/usr/bin/python3
# Playwright (canemu web's browser test) drives Debian's chromium: it never downloads a browser.
export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1
want=$(cat requirements.txt requirements-lin.txt requirements-dbc.txt client/python/pyproject.toml | sha256sum | cut -d' ' -f1)
make_venv() {  # DIR, then venv options
  local dir=$1
  shift
  local stamp=$dir/.requirements.sha256
  if [ -x "$dir/bin/python" ] && [ "$(cat "$stamp" 2>/dev/null)" = "$want" ]; then
    return
  fi
  echo "deps: creating the Python venv at $dir"
  rm -rf "$dir"
  "$py" -m venv "$@" "$dir"
  if [ "$dir" = .venv ]; then
    "$dir/bin/pip" install --quiet --disable-pip-version-check -r requirements.txt
  else
    "$dir/bin/pip" install --quiet --disable-pip-version-check -r requirements-lin.txt
    "$dir/bin/pip" install --quiet --disable-pip-version-check --no-deps -r requirements-dbc.txt
  fi
  "$dir/bin/pip" install --quiet --disable-pip-version-check --no-deps -e client/python
  echo "$want" > "$stamp"
  did_something=1
}
make_venv .venv
make_venv .venv-debian --system-site-packages

if [ "$did_something" -eq 0 ]; then
  echo "deps: everything is already installed; nothing to do"
fi
