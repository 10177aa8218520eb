#!/usr/bin/env bash
# The Cortex-M drive image over Modbus RTU, as a drive maker's drive is used (issue 69): started by
# scripts/firmware-drive BOARD on a fresh flash file, the host CLI (`dyncal table`, `dyncal flash`;
# libmodbus's RTU client on the image's pty) reads its factory table, flashes a calibrated er20
# table (read back identical), is refused a table for another robot (exit 3, the active table
# unchanged); after `SECONDS_OF_NOISE` s of random bytes on the line it still answers with the
# table unchanged; after qemu is stopped and started again on the same flash file, the flashed
# table is active with its CRC ok.
#   tests/firmware_drive.sh BOARD DYNCAL SECONDS_OF_NOISE
set -euo pipefail
board=$1 dyncal=$2 noise=$3
root="$(cd "$(dirname "$0")/.." && pwd)"
if [ ! -x "$dyncal" ]; then
  echo "FAIL: no host CLI at $dyncal (build the release preset first: scripts/build dyncal)"
  exit 1
fi
work=$(mktemp -d)
drive_pid=""
cleanup() {
  if [ -n "$drive_pid" ]; then
    kill "$drive_pid" 2> /dev/null || true
    wait "$drive_pid" 2> /dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  exit 1
}

start_drive() {
  rm -f "$work/ready"
  "$root/scripts/firmware-drive" "$board" --flash "$work/flash.bin" --ready-file "$work/ready" >> "$work/drive.log" 2>&1 &
  drive_pid=$!
  for _ in $(seq 1 600); do
    [ -s "$work/ready" ] && break
    kill -0 "$drive_pid" 2> /dev/null || fail "the drive image did not start: $(cat "$work/drive.log")"
    sleep 0.1
  done
  [ -s "$work/ready" ] || fail "the drive image was not ready within 60 s"
  uri=$(cat "$work/ready")
}
stop_drive() {
  kill -TERM "$drive_pid"
  wait "$drive_pid" || true
  drive_pid=""
  for _ in $(seq 1 50); do
    pgrep -f "arg=$work/flash.bin" > /dev/null || return 0
    sleep 0.1
  done
  fail "qemu still runs after the script was stopped"
}

start_drive
"$dyncal" table --drive "$uri" > "$work/factory.txt" || fail "dyncal table on the factory table"
grep -q "48 parameters, CRC ok" "$work/factory.txt" || fail "factory table: $(head -1 "$work/factory.txt")"
grep -q "the factory table is active" "$work/drive.log" || fail "a fresh flash did not start on the factory table"

"$dyncal" flash --drive "$uri" --params "$root/tests/data/params/er20_eq7.json" > "$work/flash.txt" ||
  fail "dyncal flash: $(cat "$work/flash.txt")"
grep -q "read back and compared: identical" "$work/flash.txt" || fail "flash: $(cat "$work/flash.txt")"
"$dyncal" table --drive "$uri" > "$work/flashed.txt"
cmp -s "$work/factory.txt" "$work/flashed.txt" && fail "the flashed table reads as the factory table"

set +e
"$dyncal" flash --drive "$uri" --params "$root/tests/data/params/tx40_eq7.json" > "$work/other.txt" 2>&1
rc=$?
set -e
[ $rc -eq 3 ] || fail "a tx40 table: exit $rc, expected 3 (rejected): $(cat "$work/other.txt")"
grep -q "robot id does not match" "$work/other.txt" || fail "a tx40 table: $(cat "$work/other.txt")"
"$dyncal" table --drive "$uri" > "$work/after_other.txt"
cmp -s "$work/flashed.txt" "$work/after_other.txt" || fail "the refused table changed the active one"

# Random bytes on the line for $noise s, as fast as the pty takes them; then, once the drive has
# read them all (tcdrain: a pty buffers what a real line would not), the line is silent.
/usr/bin/python3 - "${uri#rtu:}" "$noise" << 'PY'
import os, sys, termios, time
fd = os.open(sys.argv[1], os.O_WRONLY | os.O_NOCTTY)
end = time.monotonic() + float(sys.argv[2])
sent = 0
while time.monotonic() < end:
    sent += os.write(fd, os.urandom(256))
termios.tcdrain(fd)
print(f"noise: {sent} random bytes in {sys.argv[2]} s")
PY
sleep 0.2
"$dyncal" table --drive "$uri" > "$work/after_noise.txt" || fail "no answer after the noise"
cmp -s "$work/flashed.txt" "$work/after_noise.txt" || fail "the noise changed the active table"

stop_drive
start_drive
"$dyncal" table --drive "$uri" > "$work/restarted.txt" || fail "dyncal table after the restart"
cmp -s "$work/flashed.txt" "$work/restarted.txt" || fail "after the restart the active table differs"
grep -q "CRC ok" "$work/restarted.txt" || fail "after the restart: $(head -1 "$work/restarted.txt")"
stop_drive
echo "firmware drive $board: factory table served, flashed and read back identical, another robot's table refused, ${noise} s of noise survived, the table persists across a restart"
