#!/usr/bin/env bash
# grabber_example: multislit_grabber_example's command line and messages, as a user meets them.
#  1. --help: rc 0; no --calibration, a bad number (--seconds abc): the usage on stderr, rc 2.
#  2. Frames of another size than the calibration's: the error is shown and rc is 1.
#  3. --save on a full disk (a file-size limit): rc 1, no PCD cut or empty, no temporary file.
#  4. multislit emulate on 127.0.0.1: a camera of another size, or another serial than the
#     calibration's camera_id, is refused naming both; the right one gives clouds, and killed
#     and started again mid-run, the example says it was lost and is back.
# Run as: bash grabber_example.sh <multislit> <multislit_grabber_example> <work dir>
set -u
M=$(realpath "$1")
E=$(realpath "$2")
work=$3
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
start_in "$work"
# expect RC MESSAGE COMMAND...: the command exits with RC, its output saying MESSAGE.
expect() {
  local rc=$1 message=$2
  shift 2
  "$@" >out.log 2>err.log
  local got=$?
  [[ $got == "$rc" ]] || fail "rc $got, not $rc: $*: $(cat out.log err.log | tail -5)"
  grep -q -- "$message" out.log err.log || fail "no '$message' from $*: $(cat out.log err.log)"
}

# 1. The command line.
expect 0 "usage: multislit_grabber_example" "$E" --help
expect 2 "finite number, not 'abc'" "$E" --simulate ball --seconds abc
grep -q "usage:" err.log || fail "--seconds abc: no usage on stderr"
expect 2 "--calibration FILE is needed" "$E" --sequence .
grep -q "usage:" err.log || fail "no --calibration: no usage on stderr"
expect 2 "give one of" "$E" --seconds 1
echo "command line: --help rc 0; --seconds abc, no --calibration, no source: rc 2 with the usage"

"$M" simulate --scenario cable --frames 3 --out s >/dev/null 2>&1 || fail "simulate"
"$M" calibrate --reference s/reference.png --sensor s/sensor.yaml --out c.yaml >/dev/null 2>&1 ||
  fail "calibrate"
sed 's/width: 1296/width: 648/; s/^   height: 964/   height: 482/' s/sensor.yaml >small.yaml
grep -q "width: 648" small.yaml || fail "no 648-pixel sensor file"
"$M" simulate --scenario cable --frames 3 --sensor small.yaml --out small >/dev/null 2>&1 ||
  fail "simulate with the small sensor"

# 2. Frames of another size: said, and rc 1 (not "0 clouds" and rc 0).
expect 1 "image is 648x482 but the reference was taken with a 1296x964 camera" \
  "$E" --sequence small --calibration c.yaml
grep -q "extraction errors 3" out.log || fail "the 3 frames' errors are not counted"
echo "frames of another size: $(grep '^error' err.log)"

# 3. A full disk.
(trap '' XFSZ; ulimit -f 8; "$E" --sequence s --calibration c.yaml --save pcd) >out.log 2>err.log
rc=$?
[[ $rc == 1 ]] || fail "--save on a full disk: rc $rc, not 1"
grep -q "could not write pcd/cloud_" err.log || fail "--save on a full disk: $(cat err.log)"
[[ -z $(ls -A pcd) ]] || fail "--save on a full disk left: $(ls -A pcd)"
"$E" --sequence s --calibration c.yaml --save pcd >/dev/null 2>&1 || fail "--save"
[[ $(ls pcd/*.pcd | wc -l) == 3 && -z $(find pcd -empty) ]] || fail "--save: not 3 PCD files"
echo "full disk: rc 1, no PCD left; with room: 3 PCD files"

# 4. The emulated camera. emulate NAME ARGS...: serves until killed, once it is up.
emulator=
emulate() {
  local name=$1
  shift
  "$M" emulate --scenario cable --frames 4 "$@" >"$name.log" 2>&1 &
  emulator=$!
  waitlog "$name.log" "GigE Vision camera"
}
trap '[[ -n $emulator ]] && kill $emulator 2>/dev/null; [[ -n ${example:-} ]] && kill $example 2>/dev/null' EXIT
emulate small_camera --sensor small.yaml
expect 1 "has a 648x482 sensor: it cannot send the 1296x964" \
  "$E" --camera 127.0.0.1 --calibration c.yaml --seconds 5
kill $emulator && wait $emulator 2>/dev/null
echo "a camera of another size: $(grep '^error' err.log | sed 's/.*cannot start //')"

emulate camera --sensor s/sensor.yaml --serial SENSOR-7
"$M" calibrate --reference s/reference.png --sensor s/sensor.yaml --camera-id SENSOR-3 \
  --out other.yaml >/dev/null 2>&1 || fail "calibrate --camera-id"
expect 1 "is 'SENSOR-7', not the camera 'SENSOR-3'" \
  "$E" --camera 127.0.0.1 --calibration other.yaml --seconds 5
echo "another camera: $(grep '^error' err.log | sed 's/.*cannot start //')"
"$M" calibrate --reference s/reference.png --sensor s/sensor.yaml --camera-id SENSOR-7 \
  --out same.yaml >/dev/null 2>&1 || fail "calibrate --camera-id"
"$E" --camera 127.0.0.1 --calibration same.yaml --seconds 300 >run.log 2>&1 &
example=$!
waitlog run.log "^[1-9][0-9]* clouds,"
kill -9 $emulator && wait $emulator 2>/dev/null  # the camera dies
waitlog run.log "status: GigE Vision camera 127.0.0.1 lost (loss 1)"
emulate camera_again --sensor s/sensor.yaml --serial SENSOR-7
waitlog run.log "status: GigE Vision camera 127.0.0.1 is back (reconnect 1)"
clouds() { sed -n 's/^\([0-9]*\) clouds, .*/\1/p' run.log | tail -1; }
at_loss=$(clouds)
for _ in $(seq 1 600); do  # clouds again from the camera that came back
  [[ $(clouds) -gt $at_loss ]] && break
  sleep 0.1
done
[[ $(clouds) -gt $at_loss ]] || fail "no cloud after the camera came back: $(tail -3 run.log)"
kill -INT $example
wait $example
rc=$?
example=
[[ $rc == 130 ]] || fail "the example after Ctrl-C: rc $rc, not 130: $(tail -3 run.log)"
# Every loss ends in a reconnect, but for one the Ctrl-C may cut short, and the summary counts the
# reconnects. On a busy machine the camera that came back can miss a second too and be lost and
# reopened again, or lost once more just before the Ctrl-C: neither is an error.
losses=$(grep -c "^status: GigE Vision camera 127.0.0.1 lost (loss" run.log)
backs=$(grep -c "^status: GigE Vision camera 127.0.0.1 is back (reconnect" run.log)
pending=0
[[ $(grep "^status: GigE Vision camera 127.0.0.1" run.log | tail -1) == *"lost (loss"* ]] && pending=1
((losses >= 1 && backs >= 1 && backs + pending == losses)) ||
  fail "$losses losses, $backs reconnects: $(tail -3 run.log)"
grep -q "reconnects $backs," run.log || fail "the summary does not count $backs reconnects: $(tail -3 run.log)"
echo "camera killed and back: $(grep '^status' run.log | tr '\n' ';') $(grep '^[0-9]* clouds;' run.log)"
echo "grabber_example: all checks passed"
