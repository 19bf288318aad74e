# Shell functions for the tests that run inside a guest (guest-tests.sh under busybox,
# systemd-tests.sh under Debian's dash). Each test prints GUEST-PASS or GUEST-FAIL with what it
# expected and got; guest_summary prints the count the host reads.
pass=0
fail=0

result() {  # NAME EXPECTED GOT
  if [ "$2" = "$3" ]; then
    echo "GUEST-PASS $1"
    pass=$((pass + 1))
  else
    echo "GUEST-FAIL $1"
    echo "  expected: $2"
    echo "  got:      $3"
    fail=$((fail + 1))
  fi
}

guest_summary() {
  echo "GUEST-RESULT: $pass passed, $fail failed"
}

uptime_cs() {  # the guest's uptime in hundredths of a second
  tr -d . </proc/uptime | cut -d' ' -f1
}

nap() {  # 10 ms (busybox has usleep, Debian's coreutils a fractional sleep)
  usleep 10000 2>/dev/null || sleep 0.01
}

wait_for() {  # COMMAND...: until it succeeds, for at most 20 s (WAIT_SECONDS)
  deadline=$(($(uptime_cs) + ${WAIT_SECONDS:-20} * 100))
  while ! "$@" 2>/dev/null; do
    [ "$(uptime_cs)" -gt "$deadline" ] && return 1
    nap
  done
}

wait_pid() {  # PID [SECONDS]: until the process ends; killed after SECONDS (default 10)
  deadline=$(($(uptime_cs) + ${2:-10} * 100))
  while kill -0 "$1" 2>/dev/null; do
    if [ "$(uptime_cs)" -gt "$deadline" ]; then
      kill "$1"
      echo "  (process $1 killed after ${2:-10} s)"
      return 1
    fi
    nap
  done
}

# Sockets of can-utils listening on an interface, from the kernel's receive lists.
receivers() {
  grep -c " $1 " /proc/net/can/rcvlist_all
}
more_receivers() {  # INTERFACE COUNT
  [ "$(receivers "$1")" -gt "$2" ]
}
listening() {  # FILE: canemu dump/record said it listens
  grep -q listening "$1"
}
