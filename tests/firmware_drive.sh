#!/usr/bin/env bash
# The Cortex-M drive image over Modbus RTU, as a drive maker's drive is used (issue 69), with the
# host CLI (libmodbus's RTU client on the image's pty). Started by scripts/firmware-drive BOARD on a
# fresh flash file, the image
# - serves its factory table;
# - is calibrated by `dyncal calibrate` at 1 kHz (excitation, estimation, fit, flash, verification
#   on its simulated arm) with no sample lost, its own model error on the fresh trajectory down by
#   at least 90 % on every joint, the table read back identical;
# - takes identify's fit of the calibration log and the collision monitor's thresholds from its
#   residual (`dyncal monitor --drive`), and plays a watched run of a trajectory the calibration
#   never saw without a false alarm;
# - refuses a table for another robot (exit 3, the active table unchanged);
# - survives SECONDS_OF_NOISE s of random bytes on its line (the table unchanged, the next request
#   answered);
# - after qemu is stopped and started again on the same flash file, with a 5 kg load on the arm's
#   last link, has the same table active with its CRC ok, and `dyncal payload --drive` finds the
#   load (written into the table; the mass within 3 std, the centre of mass within 5 mm);
# - flashes a table of its other model (Eq. 7 only) and reads it back identical.
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
  "$root/scripts/firmware-drive" "$board" --flash "$work/flash.bin" --ready-file "$work/ready" "$@" >> "$work/drive.log" 2>&1 &
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

# Calibration from the factory table: 2 excitation periods of 10 s and two verification runs of
# one period, sampled at the control rate (1 kHz: the collision monitor's statistics below need
# it), in lockstep.
"$dyncal" calibrate --robot er20 --drive "$uri" --save-log "$work/excitation.csv" --report "$work/calibrate.json" \
  > "$work/calibrate.txt" 2>&1 || fail "dyncal calibrate: $(cat "$work/calibrate.txt")"
/usr/bin/python3 - "$work/calibrate.json" << 'PY' || fail "calibrate: $(cat "$work/calibrate.txt")"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["flashed"] and r["lost"] == 0 and r["samples"] == 20000, (r["flashed"], r["lost"], r["samples"])
for j in r["joints"]:
    before, after = j["drive_error_before"], j["drive_error_after"]
    assert after <= 0.1 * before, f"joint {j['joint']}: model error {before:.3f} -> {after:.3f} Nm"
    print(f"joint {j['joint']}: drive model error {before:.3f} -> {after:.3f} Nm ({100 * (1 - after / before):.1f} % less)")
PY
grep -q "read back and compared: identical" "$work/calibrate.txt" || fail "calibrate's flash: $(cat "$work/calibrate.txt")"

# The collision monitor: identify's fit of the calibration log flashed, the thresholds for 0.01
# false alarms per hour from its residual written, and a watched calibration run on another
# trajectory (seed 3), left unflashed, completes.
"$dyncal" identify --robot er20 --data "$work/excitation.csv" --params "$work/params.json" > "$work/identify.txt" 2>&1 ||
  fail "dyncal identify: $(cat "$work/identify.txt")"
"$dyncal" flash --drive "$uri" --params "$work/params.json" > "$work/flash_fit.txt" 2>&1 ||
  fail "dyncal flash: $(cat "$work/flash_fit.txt")"
"$dyncal" monitor --robot er20 --drive "$uri" --params "$work/params.json" > "$work/monitor.txt" 2>&1 ||
  fail "dyncal monitor --drive: $(cat "$work/monitor.txt")"
grep -q "written to the drive's collision monitor" "$work/monitor.txt" || fail "monitor: $(cat "$work/monitor.txt")"
"$dyncal" calibrate --robot er20 --drive "$uri" --seed 3 --periods 1 --no-flash > "$work/watched.txt" 2>&1 ||
  fail "a watched run: $(cat "$work/watched.txt")"
"$dyncal" table --drive "$uri" > "$work/flashed.txt"
grep -q "58 parameters, CRC ok" "$work/flashed.txt" || fail "calibrated table: $(head -1 "$work/flashed.txt")"

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
start_drive --payload 5,0,0,0.1
"$dyncal" table --drive "$uri" > "$work/restarted.txt" || fail "dyncal table after the restart"
cmp -s "$work/flashed.txt" "$work/restarted.txt" || fail "after the restart the active table differs"
grep -q "CRC ok" "$work/restarted.txt" || fail "after the restart: $(head -1 "$work/restarted.txt")"
"$dyncal" payload --robot er20 --drive "$uri" --report "$work/payload.json" > "$work/payload.txt" 2>&1 ||
  fail "dyncal payload --drive: $(cat "$work/payload.txt")"
/usr/bin/python3 - "$work/payload.json" << 'PY' || fail "payload: $(cat "$work/payload.txt")"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["state"] == "written", r["state"]
m, s = r["standard"][9]["value"], r["standard"][9]["std"]
assert abs(m - 5) <= 3 * s, f"mass {m} +- {s} kg, the load is 5 kg"
mz = r["standard"][8]["value"]
assert abs(mz / m - 0.1) <= 0.005, f"centre of mass z {mz / m} m, the load's is 0.1 m"
print(f"payload: {m:.4f} +- {s:.4f} kg at z = {mz / m:.4f} m (the load: 5 kg at 0.1 m)")
PY
"$dyncal" flash --drive "$uri" --params "$root/tests/data/params/er20_eq7.json" > "$work/flash.txt" ||
  fail "dyncal flash: $(cat "$work/flash.txt")"
grep -q "read back and compared: identical" "$work/flash.txt" || fail "flash: $(cat "$work/flash.txt")"
stop_drive
grep "run finished" "$work/drive.log" | tail -1
echo "firmware drive $board: factory table served; calibrated at 1 kHz (0 samples lost, model error down >= 90 % on every joint, read back identical); collision monitor set, a watched run without a false alarm; another robot's table refused; ${noise} s of noise survived; the table persists across a restart; a 5 kg load found by payload --drive; an Eq. 7 table flashed"
