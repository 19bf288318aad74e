#!/usr/bin/env bash
# Every component's README says what is in it: each of its source folders (by its name and a '/',
# e.g. `world/`) and each public header (by its file name) must be named in it. Usage:
#   check-readmes.sh [ROOT]      check the tree at ROOT (default: this repository)
#   check-readmes.sh --self-test plant an unnamed folder and an unnamed header in a scratch copy
#                                and check that both are reported
set -u

check() {
  local root=$1 status=0 component readme item
  cd "$root" || return 2
  for component in vendor_abi firmware_model ipc daemon client client/python; do
    readme=$component/README.md
    if [ ! -f "$readme" ]; then
      echo "$component: no README.md"
      status=1
      continue
    fi
    # Folders that hold sources (not build output, not caches), below the component.
    while IFS= read -r item; do
      if ! grep -qF "$(basename "$item")/" "$readme"; then
        echo "$readme does not name the folder $item"
        status=1
      fi
    done < <(git ls-files "$component" | grep -vE '(^|/)(build|tests?|__pycache__|[^/]*\.egg-info)/' |
             { if [ "$component" = client ]; then grep -v '^client/python/'; else cat; fi; } |
             xargs -r -n1 dirname | sort -u | grep -vx "$component")
    # Public headers, and the Python package's modules.
    while IFS= read -r item; do
      if ! grep -qF "$(basename "$item")" "$readme"; then
        echo "$readme does not name $item"
        status=1
      fi
    done < <(git ls-files "$component/include" 2>/dev/null | grep -E '\.(h|hpp)$'
             [ "$component" = client/python ] && git ls-files "$component" | grep -E '\.py$' |
               grep -vE '(^|/)(build|tests?)/|__init__\.py$')
  done
  [ $status -eq 0 ] && echo "readmes: every component's README names its folders, public headers and modules"
  return $status
}

self_test() {
  local here scratch failures=0
  here=$(cd "$(dirname "$0")/.." && pwd)
  scratch=$(mktemp -d)
  trap 'rm -rf "$scratch"' RETURN
  git clone -q "$here" "$scratch/tree"
  for planted in daemon/src/planted_room/x.cpp daemon/include/canemu/daemon/base/planted.hpp; do
    (cd "$scratch/tree" && mkdir -p "$(dirname "$planted")" && echo "// planted" >"$planted" &&
      git add -f "$planted")
    if (check "$scratch/tree" >/dev/null); then
      echo "self-test: not reported: $planted"
      failures=$((failures + 1))
    fi
    (cd "$scratch/tree" && git rm -q -f "$planted")
  done
  [ $failures -eq 0 ] && echo "self-test: an unnamed folder and an unnamed header are reported"
  return $((failures > 0))
}

if [ "${1:-}" = "--self-test" ]; then
  self_test
else
  check "${1:-$(dirname "$0")/..}"
fi
