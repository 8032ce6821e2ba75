#!/usr/bin/env bash
# record_command: `multislit record` on the emulated GigE Vision camera (127.0.0.1), as a user
# runs it.
#  1. A camera whose PTP clock runs on TAI: record 12 frames; frames.csv's stamps are the host's
#     UTC (the 37 s applied), their clock "camera"; sensor.yaml and calibration.yaml written.
#  2. The same camera live through map --camera, and the recording replayed through
#     map --sequence: the same decisions frame by frame; summary.txt names the time base.
#  3. Mono12 frames as 16-bit PNGs; Ctrl-C leaves every file whole; errors name the option.
# Run as: bash record_command.sh <multislit> <work dir>
set -u
M=$1
work=$2
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
start_in "$work"

"$M" simulate --scenario ball --frames 0 --out sim >/dev/null 2>&1 || fail "simulate"
"$M" calibrate --reference sim/reference.png --sensor sim/sensor.yaml --out calib.yaml \
  >/dev/null 2>&1 || fail "calibrate"

# emulate NAME ARGS...: a fresh camera serving the ball walk's 8 frames at 10 Hz, once it is up.
emulator=
emulate() {
  local name=$1
  shift
  "$M" emulate --scenario ball --frames 8 --fps 10 --seconds 300 "$@" >"$name.log" 2>&1 &
  emulator=$!
  waitlog "$name.log" "GigE Vision camera"
}
stop_emulator() {
  kill $emulator 2>/dev/null
  wait $emulator 2>/dev/null
  emulator=
}
trap '[[ -n $emulator ]] && kill $emulator 2>/dev/null' EXIT
now_s() { date +%s; }

# 1. Record from a camera on TAI.
emulate tai --ptp --clock-offset 37
before=$(now_s)
"$M" record --camera 127.0.0.1 --calibration calib.yaml --sensor sim/sensor.yaml --fps 10 \
  --frames 12 --out rec >record.log 2>record.err || fail "record: $(tail -3 record.log record.err)"
after=$(now_s)
stop_emulator
cat record.log
grep -q "recorded 12 frames" record.log || fail "record: not 12 frames"
grep -q "stamps: camera PTP clock, TAI-UTC offset 37 s applied" record.log || fail "no time base"
[[ $(ls rec/frame_*.png | wc -l) == 12 ]] || fail "not 12 PNG frames: $(ls rec)"
[[ -s rec/sensor.yaml && -s rec/calibration.yaml && ! -e rec/odometry.csv ]] ||
  fail "recording files: $(ls rec)"
[[ $(head -1 rec/frames.csv) == "frame,file,stamp_us,clock" ]] || fail "frames.csv header"
[[ $(grep -c ',camera$' rec/frames.csv) == 12 ]] || fail "stamps not all from the camera"
file rec/frame_000000.png | grep -q "8-bit grayscale" || fail "Mono8 frame: $(file rec/frame_000000.png)"
# Each stamp within the recording's run on the host's UTC clock (1 s of slack for rounding).
awk -F, -v lo=$((before - 1)) -v hi=$((after + 1)) 'NR > 1 && ($3 / 1e6 < lo || $3 / 1e6 > hi) {
  print "frame " $1 ": stamp " $3 " outside [" lo ", " hi "] s"; bad = 1 } END { exit bad }' \
  rec/frames.csv || fail "stamps not on UTC"
grep -q "record: 12 frames" record.err || fail "no progress on stderr: $(cat record.err)"
echo "record: 12 frames, stamps on UTC within [$before, $after] s"

# 2. The same camera live, and the recording replayed: the same decisions.
emulate live --ptp --clock-offset 37
"$M" map --camera 127.0.0.1 --calibration calib.yaml --sensor sim/sensor.yaml --fps 10 \
  --frames 12 --out live >live.log 2>&1 || fail "map --camera: $(tail -3 live.log)"
stop_emulator
grep -q "stamps: camera PTP clock, TAI-UTC offset 37 s applied" live/summary.txt ||
  fail "summary.txt names no time base: $(head -3 live/summary.txt)"
"$M" map --sequence rec --calibration rec/calibration.yaml --out replay >replay.log 2>&1 ||
  fail "map --sequence: $(tail -3 replay.log)"
grep -q "12 processed" replay/summary.txt || fail "replay: not 12 frames"
# Columns 3-14: pose, decision, reason, floor, points, sigma, obstacles, groups, nearest, map.
decisions() { tail -n +2 "$1" | cut -d, -f3-14; }
diff <(decisions live/decisions.csv) <(decisions replay/decisions.csv) >decisions.diff ||
  fail "live and replayed decisions differ: $(head -5 decisions.diff)"
[[ $(decisions live/decisions.csv | wc -l) == 12 ]] || fail "live: not 12 decisions"
diff <(tail -n +2 rec/frames.csv | cut -d, -f3) <(tail -n +2 replay/decisions.csv | cut -d, -f2) \
  >/dev/null || fail "the replay's stamps are not the recorded ones"
echo "live and replayed: the same 12 decisions ($(decisions live/decisions.csv | cut -d, -f4 |
  sort | uniq -c | xargs))"

# 3. Mono12 as 16-bit PNGs of a camera without PTP: host stamps.
emulate mono12 --bit-depth 16
"$M" record --camera 127.0.0.1 --sensor sim/sensor.yaml --pixel-format Mono12 --exposure 2000 \
  --gain 2 --frames 3 --out rec12 >rec12.log 2>&1 || fail "record Mono12: $(tail -3 rec12.log)"
file rec12/frame_000000.png | grep -q "16-bit grayscale" || fail "Mono12: $(file rec12/frame_000000.png)"
[[ $(grep -c ',host$' rec12/frames.csv) == 3 ]] || fail "Mono12: stamps not the host's"
grep -q "stamps: host clock" rec12.log || fail "Mono12: $(cat rec12.log)"
echo "Mono12: 3 16-bit PNG frames, host clock"

# Ctrl-C: rc 130, frames.csv whole, one row a PNG.
"$M" record --camera 127.0.0.1 --sensor sim/sensor.yaml --out interrupted >int.log 2>&1 &
recorder=$!
for _ in $(seq 1 600); do
  [[ $(ls interrupted/frame_*.png 2>/dev/null | wc -l) -ge 3 ]] && break
  sleep 0.1
done
kill -INT $recorder
wait $recorder
rc=$?
[[ $rc == 130 ]] || fail "record after Ctrl-C: rc $rc: $(tail -3 int.log)"
rows=$(($(wc -l <interrupted/frames.csv) - 1))
[[ $rows -ge 3 && $rows == $(ls interrupted/frame_*.png | wc -l) ]] ||
  fail "Ctrl-C: $rows rows for $(ls interrupted/frame_*.png | wc -l) frames"
[[ -z $(ls -a interrupted | grep -v -E '^(\.|\.\.|frame_[0-9]{6}\.png|frames\.csv|sensor\.yaml)$') ]] ||
  fail "Ctrl-C left: $(ls -a interrupted)"
echo "Ctrl-C: rc 130, $rows whole rows and frames"

# Errors: what the camera refuses, and the options.
refused_with 1 "the camera takes ExposureTime (or ExposureTimeAbs) from 10 to 1e+07 us" \
  "$M" record --camera 127.0.0.1 --sensor sim/sensor.yaml --exposure 5 --frames 1 --out bad
stop_emulator
refused_with 1 "cannot open camera 127.0.0.1" "$M" record --camera 127.0.0.1 --frames 1 --out nocam
[[ ! -e nocam ]] || fail "a camera that cannot be opened left: $(ls nocam)"
refused_with 2 "give --frames or --seconds, not both" \
  "$M" record --camera 127.0.0.1 --frames 3 --seconds 1 --out bad
refused_with 2 "--pixel-format must be Mono8, Mono12 or Mono16, not 'Mono10'" \
  "$M" record --camera 127.0.0.1 --pixel-format Mono10 --out bad
refused_with 2 "--ptp-utc-offset: AravisConfig.ptp_utc_offset_s must be in [-86400, 86400]" \
  "$M" record --camera 127.0.0.1 --ptp-utc-offset 1e6 --out bad
refused_with 2 "already holds a recording" "$M" record --camera 127.0.0.1 --out rec
refused_with 2 "--out DIR is needed" "$M" record --camera 127.0.0.1
refused_with 2 "--exposure sets a live camera: it needs --camera" \
  "$M" map --sequence rec --calibration rec/calibration.yaml --exposure 100 --out bad
"$M" record --help | grep -q -- "--ptp-utc-offset" || fail "record --help: no --ptp-utc-offset"
echo "errors: $refused_count refused with a message naming the option"
echo "record_command: all checks passed"
