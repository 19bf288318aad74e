#!/usr/bin/env bash
# Checks the dependency rules of ARCHITECTURE.md that a grep can see:
# firmware_model is pure (no I/O, threads, wall clocks, logging) and includes nothing of ours
# but itself.
set -u
root=${1:-$(dirname "$0")/..}
cd "$root" || exit 2
forbidden='#include *<(thread|mutex|condition_variable|future|atomic|fstream|iostream|cstdio|stdio\.h|ctime|time\.h|filesystem|sys/[a-z_]+\.h|unistd\.h|fcntl\.h|pthread\.h|syslog\.h)>'
bad=$(grep -rnE "$forbidden" firmware_model || true)
# Deterministic PRNGs from <random> and chrono durations are fine; their wall-clock and
# entropy sources are not.
bad+=$(grep -rnE '(steady_clock|system_clock|high_resolution_clock|random_device|getenv|std::cout|std::cerr)' firmware_model || true)
ours=$(grep -rnE '#include *[<"]canemu/' firmware_model | grep -v 'canemu/firmware_model/' || true)
status=0
if [ -n "$bad" ]; then
  echo "firmware_model must not do I/O, threading, wall-clock time or logging:"; echo "$bad"; status=1
fi
if [ -n "$ours" ]; then
  echo "firmware_model may include only its own headers:"; echo "$ours"; status=1
fi
# ipc depends on libc only; client on ipc only (never on model types), except its tools
# (client/tools: the canemu command line), which use the wire model but never the daemon.
upward=$(grep -rnE '#include *[<"]canemu/(firmware_model|daemon|client)/' ipc 2>/dev/null || true)
upward+=$(grep -rnE --exclude-dir=tools '#include *[<"]canemu/(firmware_model|daemon)/' client 2>/dev/null || true)
upward+=$(grep -rnE '#include *[<"]canemu/daemon/' client/tools 2>/dev/null || true)
if [ -n "$upward" ]; then
  echo "ipc may include only ipc; client only client and ipc; client/tools also the model:"
  echo "$upward"; status=1
fi
[ $status -eq 0 ] && echo "layering: firmware_model is pure, ipc and client stay below the model"
exit $status
