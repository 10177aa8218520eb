#!/bin/sh
# CTest fixture for a simulated drive (or a socat pty pair): started in the background, ready when
# its ready file appears (the drive writes it atomically once it serves requests), stopped by PID.
#   drive_fixture.sh start DIR NAME DYNCAL [--real-time] [drive options...]
#     (the drive runs in lockstep unless --real-time comes first)
#   drive_fixture.sh pty DIR NAME              (socat pty pair: DIR/NAME.a <-> DIR/NAME.b)
#   drive_fixture.sh relay DIR NAME RELAY BAUD (a serial line at BAUD: DIR/NAME.drive <-> DIR/NAME.host)
#   drive_fixture.sh stop DIR NAME
set -eu
action=$1 dir=$2 name=$3
shift 3
mkdir -p "$dir"
wait_for() {  # wait_for FILE PID: poll the handshake file while the process lives (30 s limit)
  i=0
  while [ ! -e "$1" ]; do
    if ! kill -0 "$2" 2>/dev/null; then echo "process $2 exited before $1 appeared" >&2; cat "$dir/$name.log" >&2; exit 1; fi
    i=$((i + 1))
    if [ "$i" -gt 600 ]; then echo "timeout waiting for $1" >&2; exit 1; fi
    sleep 0.05
  done
}
claim() {  # claim: refuse a name whose fixture still runs (two fixtures sharing DIR/NAME.* files would
  # overwrite each other's pid file, and the first one's stop would then leave its process running)
  if [ -e "$dir/$name.pid" ] && kill -0 "$(cat "$dir/$name.pid")" 2>/dev/null; then
    echo "fixture $name is already running (pid $(cat "$dir/$name.pid"), $dir/$name.pid): two fixtures share a name, or a run left it" >&2
    exit 1
  fi
}
case "$action" in
  start | pty | relay) claim ;;
esac
case "$action" in
  start)
    dyncal=$1
    shift
    clock=--lockstep
    if [ "${1:-}" = --real-time ]; then clock=; shift; fi
    rm -f "$dir/$name.ready" "$dir/$name.table" "$dir/$name.table.tmp"
    "$dyncal" drive --ready-file "$dir/$name.ready" --table "$dir/$name.table" $clock "$@" >"$dir/$name.log" 2>&1 &
    echo $! >"$dir/$name.pid"
    wait_for "$dir/$name.ready" "$(cat "$dir/$name.pid")"
    ;;
  pty)
    rm -f "$dir/$name.a" "$dir/$name.b"
    socat -d -d "pty,raw,echo=0,link=$dir/$name.a" "pty,raw,echo=0,link=$dir/$name.b" >"$dir/$name.log" 2>&1 &
    echo $! >"$dir/$name.pid"
    wait_for "$dir/$name.b" "$(cat "$dir/$name.pid")"
    wait_for "$dir/$name.a" "$(cat "$dir/$name.pid")"
    ;;
  relay)
    rm -f "$dir/$name.drive" "$dir/$name.host" "$dir/$name.ready"
    "$1" "$2" "$dir/$name.drive" "$dir/$name.host" "$dir/$name.ready" >"$dir/$name.log" 2>&1 &
    echo $! >"$dir/$name.pid"
    wait_for "$dir/$name.ready" "$(cat "$dir/$name.pid")"
    ;;
  stop)
    pid=$(cat "$dir/$name.pid")
    kill "$pid" 2>/dev/null || true
    i=0
    while kill -0 "$pid" 2>/dev/null; do
      i=$((i + 1))
      if [ "$i" -gt 200 ]; then kill -9 "$pid" 2>/dev/null || true; fi
      sleep 0.05
    done
    rm -f "$dir/$name.pid"
    ;;
esac
