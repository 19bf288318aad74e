#!/usr/bin/env bash
# Checks the dependency rules of ARCHITECTURE.md that a grep can see. Usage:
#   check-layering.sh [ROOT]      check the tree at ROOT (default: this repository)
#   check-layering.sh --self-test plant one violation of each rule in a scratch tree and check
#                                 that every one is reported
set -u

# Every include line under DIR (recursively) that matches the extended regex PATTERN.
includes() {  # DIR PATTERN
  [ -d "$1" ] || return 0
  grep -rnE --include='*.[ch]' --include='*.[ch]pp' --include='*.inc' "#include *[<\"]$2" "$1" || true
}

check() {
  local root=$1 status=0
  cd "$root" || return 2
  local fm=firmware_model inc=firmware_model/include/canemu/firmware_model src=firmware_model/src
  report() {  # MESSAGE FINDINGS
    if [ -n "$2" ]; then
      echo "$1"
      echo "$2"
      status=1
    fi
  }

  # 1. The model is pure: no I/O, threads, wall clocks, entropy or logging.
  local forbidden='(thread|mutex|condition_variable|future|atomic|fstream|iostream|cstdio|stdio\.h|ctime|time\.h|filesystem|sys/[a-z_]+\.h|unistd\.h|fcntl\.h|pthread\.h|syslog\.h)>'
  local bad
  bad=$(includes $fm "$forbidden")
  bad+=$(grep -rnE '(steady_clock|system_clock|high_resolution_clock|random_device|getenv|std::cout|std::cerr)' $fm || true)
  report "firmware_model must not do I/O, threading, wall-clock time or logging:" "$bad"

  # 2. The model includes nothing of ours but itself.
  report "firmware_model may include only its own headers:" \
    "$(includes $fm 'canemu/' | grep -v 'canemu/firmware_model/')"

  # 3. Rooms of the model: sim <- bus <- chips <- adapters. A room includes only rooms below it
  #    (public headers by their canemu/firmware_model/ path, private ones by their src/ path).
  local room below
  for room in sim bus chips; do
    case $room in
      sim) below='sim' ;;
      bus) below='sim|bus' ;;
      chips) below='sim|bus|chips' ;;
    esac
    report "firmware_model/$room may include only $below:" \
      "$( (includes $inc/$room 'canemu/firmware_model/'; includes $src/$room 'canemu/firmware_model/') |
          grep -vE "#include *[<\"]canemu/firmware_model/($below)/")$( (includes $inc/$room '(sim|bus|chips|adapters)/'
          includes $src/$room '(sim|bus|chips|adapters)/') | grep -vE "[<\"](canemu/firmware_model/)?($below)/")"
  done

  # 4. The vendor headers (vendor_abi/: VCI, SORCUS) are a leaf: they include only each other and
  #    the C library. The model speaks their data types, never their APIs (the client's).
  local vendor
  for vendor in vci sorcus; do
    report "vendor_abi/include/$vendor (vendor headers) may include only each other:" \
      "$(includes vendor_abi/include/$vendor '' | grep -vE "#include *[<\"](($vendor/)?[a-z0-9_]+\.h|std[a-z]+\.h)[\">]")"
  done
  report "firmware_model may include of the vendor headers only the data types:" \
    "$(includes $fm '((vci|sorcus)/)?(vcinpl[a-z0-9_]*|vcisdk|canemu_vci|canemu_events|xcan|sl64lib)\.h')"

  # 5. ipc includes only ipc; the client libraries only client and ipc; the CLI (client/tools)
  #    also the model, never the daemon; the daemon never the client.
  report "ipc may include only ipc:" "$(includes ipc 'canemu/(firmware_model|daemon|client)/')"
  report "client libraries may include only client and ipc:" \
    "$(includes client 'canemu/(firmware_model|daemon)/' | grep -v '^client/tools/')"
  report "client/tools may include client, ipc and the model, never the daemon:" \
    "$(includes client/tools 'canemu/daemon/')"
  report "the daemon may not include the client:" "$(includes daemon 'canemu/client/')"

  # 6. Rooms of the daemon (ARCHITECTURE.md, "Inside canemud"): a room includes only the rooms
  #    it points to (public headers by their canemu/daemon/ROOM/ path, private ones by ROOM/).
  local dinc=daemon/include/canemu/daemon dsrc=daemon/src
  for room in base config bridges restbus world distributed vci sorcus control loop; do
    case $room in
      base) below='base' ;;
      config) below='config' ;;
      bridges) below='base|config|bridges' ;;
      restbus) below='base|config|restbus' ;;
      world) below='base|config|bridges|restbus|world' ;;
      distributed) below='base|config|bridges|restbus|world|distributed' ;;
      vci) below='base|config|world|vci' ;;
      sorcus) below='base|config|world|sorcus' ;;
      control) below='base|config|bridges|restbus|world|distributed|vci|sorcus|control' ;;
      loop) below='base|config|bridges|restbus|world|distributed|vci|sorcus|control|loop' ;;
    esac
    report "daemon/$room may include only $below:" \
      "$( (includes $dinc/$room 'canemu/daemon/'; includes $dsrc/$room 'canemu/daemon/') |
        grep -vE "#include *[<\"]canemu/daemon/($below)/"
        (includes $dinc/$room '[a-z_]+/[a-z_]+\.hpp'; includes $dsrc/$room '[a-z_]+/[a-z_]+\.hpp') |
        grep -E '#include *"' | grep -vE '#include *"canemu/' | grep -vE "\"($below)/")"
  done
  report "daemon headers must be in a room (daemon/include/canemu/daemon/ROOM/):" \
    "$(find $dinc -maxdepth 1 -name '*.hpp' 2>/dev/null)$(includes daemon 'canemu/daemon/[a-z_]+\.hpp')"

  # 7. No include circle between the daemon's files: a file and its header are one unit, and
  #    the units' includes form no cycle.
  report "include circle in the daemon:" "$(python3 - daemon <<'PY'
import os, re, sys
# A unit is a public header and the sources of the same name; a private header (under src/)
# belongs to whoever includes it: its includes count as theirs.
public, files = set(), {}
for d, _, fs in os.walk(sys.argv[1]):
    for f in fs:
        if f.endswith(('.cpp', '.hpp')):
            name = os.path.splitext(f)[0]
            files.setdefault(name, []).append(os.path.join(d, f))
            if f.endswith('.hpp') and '/include/' in d:
                public.add(name)
inc = re.compile(r'#include *"(?:canemu/daemon/)?(?:[a-z_]+/)?([a-z_]+)\.hpp"')
def reach(name, seen):
    out = set()
    for p in files.get(name, []):
        for m in inc.finditer(open(p).read()):
            n = m.group(1)
            if n in public:
                out.add(n)
            elif n in files and n not in seen:
                seen.add(n)
                out |= reach(n, seen)
    return out
edges = {u: reach(u, {u}) - {u} for u in public}
state = {}
def visit(u, path):
    state[u] = 1
    for v in sorted(edges[u]):
        if state.get(v) == 1:
            print(' -> '.join(path[path.index(v):] + [v]))
        elif v not in state:
            visit(v, path + [v])
    state[u] = 2
for u in sorted(public):
    if u not in state:
        visit(u, [u])
PY
)"

  [ $status -eq 0 ] &&
    echo "layering: the model is pure and layered (sim <- bus <- chips <- adapters), the vendor headers are a leaf, ipc/client/tools/daemon keep their arrows, the daemon's rooms theirs, no include circle"
  return $status
}

self_test() {
  local here scratch failures=0
  here=$(cd "$(dirname "$0")/.." && pwd)
  scratch=$(mktemp -d)
  trap 'rm -rf "$scratch"' RETURN
  # One violation per rule, each planted in a fresh copy of the real tree's sources.
  local -a cases=(
    "firmware_model/src/bus/planted.cpp|#include <thread>"
    "firmware_model/src/bus/planted.cpp|#include \"canemu/ipc/protocol.hpp\""
    "firmware_model/include/canemu/firmware_model/chips/planted.hpp|#include \"canemu/firmware_model/adapters/ixxat/can_line.hpp\""
    "firmware_model/src/chips/planted.cpp|#include \"adapters/ixxat/x.hpp\""
    "firmware_model/include/canemu/firmware_model/bus/planted.hpp|#include \"canemu/firmware_model/chips/hosted_node.hpp\""
    "firmware_model/include/canemu/firmware_model/sim/planted.hpp|#include \"canemu/firmware_model/bus/frame.hpp\""
    "vendor_abi/include/vci/planted.h|#include \"canemu/firmware_model/bus/frame.hpp\""
    "firmware_model/src/adapters/planted.cpp|#include \"vci/vcinpl.h\""
    "ipc/src/planted.cpp|#include \"canemu/client/channel.hpp\""
    "client/src/planted.cpp|#include \"canemu/firmware_model/bus/frame.hpp\""
    "client/tools/canemu/planted.cpp|#include \"canemu/daemon/config/config.hpp\""
    "daemon/src/planted.cpp|#include \"canemu/client/channel.hpp\""
    "daemon/src/config/planted.cpp|#include \"canemu/daemon/base/log.hpp\""
    "daemon/include/canemu/daemon/world/planted.hpp|#include \"canemu/daemon/loop/server.hpp\""
    "daemon/src/vci/planted.cpp|#include \"sorcus/service_replies.hpp\""
    "daemon/include/canemu/daemon/planted.hpp|#include <string>"
    "daemon/src/world/device_registry.hpp|#include \"canemu/daemon/world/simulation.hpp\""
  )
  local c file line
  for c in "${cases[@]}"; do
    file=${c%%|*}
    line=${c#*|}
    rm -rf "$scratch/tree"
    mkdir -p "$scratch/tree"
    (cd "$here" && git ls-files -z vendor_abi firmware_model ipc client daemon | xargs -0 cp --parents -t "$scratch/tree")
    mkdir -p "$scratch/tree/$(dirname "$file")"
    echo "$line" >"$scratch/tree/$file"
    if (check "$scratch/tree" >/dev/null); then
      echo "self-test: not reported: $line in $file"
      failures=$((failures + 1))
    fi
  done
  rm -rf "$scratch/tree"
  mkdir -p "$scratch/tree"
  (cd "$here" && git ls-files -z vendor_abi firmware_model ipc client daemon | xargs -0 cp --parents -t "$scratch/tree")
  if ! (check "$scratch/tree" >/dev/null); then
    echo "self-test: the unchanged tree is reported"
    failures=$((failures + 1))
  fi
  [ $failures -eq 0 ] && echo "self-test: every planted violation was reported (${#cases[@]} rules)"
  return $((failures > 0))
}

if [ "${1:-}" = "--self-test" ]; then
  self_test
else
  check "${1:-$(dirname "$0")/..}"
fi
