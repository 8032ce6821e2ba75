#!/usr/bin/env bash
# map_command: `multislit map` end to end, as a user runs it.
#  1. A walk recorded (walk --record) and replayed (map --sequence): the same occupied voxels.
#  2. multislit emulate serving a walk as a GigE Vision camera on 127.0.0.1 -> map --camera;
#     emulate --walk rendering the demo's walk live -> map --camera --poses gait.
#  3. Bad odometry files and missing options: a clear message naming the file, and rc != 0.
# Run as: bash map_command.sh <multislit> <work dir>
set -u
multislit=$1
work=$2
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
rm -rf "$work" && mkdir -p "$work"
occupied() { sed -n 's/.*map: \([0-9]*\) occupied voxels.*/\1/p' "$1" | head -1; }

# 1. Record a walk with the ball thrown in at frame 5, replay it.
"$multislit" walk --frames 30 --ball-frame 5 --no-cable --record "$work/rec" --out "$work/walk" \
  >"$work/walk.log" 2>&1 || fail "walk --record: $(tail -3 "$work/walk.log")"
"$multislit" map --sequence "$work/rec" --calibration "$work/rec/calibration.yaml" \
  --out "$work/map" >"$work/map.log" 2>&1 || fail "map --sequence: $(tail -3 "$work/map.log")"
walked=$(occupied "$work/walk/summary.txt")
mapped=$(occupied "$work/map/summary.txt")
echo "walk: $walked occupied voxels; replayed through map --sequence: $mapped"
[[ -n $walked && $walked -gt 0 && $walked == "$mapped" ]] || fail "occupied voxels differ"
grep -q "30 processed" "$work/map/summary.txt" || fail "not all 30 frames processed"
for f in decisions.csv obstacles.csv map.bt map_top.png fig15_obstacle_points.png \
  rdmap_most_obstacles.png summary.txt; do
  [[ -s $work/map/$f ]] || fail "map wrote no $f"
done
[[ $(wc -l <"$work/map/decisions.csv") == 31 ]] || fail "decisions.csv: not 30 rows"
grep -q ",stop,sudden obstacle," "$work/map/decisions.csv" || fail "no stop for the ball"

# 2. The emulated camera on 127.0.0.1 and map --camera.
"$multislit" simulate --scenario ball --frames 0 --out "$work/sim" >/dev/null 2>&1 ||
  fail "simulate"
"$multislit" calibrate --reference "$work/sim/reference.png" --sensor "$work/sim/sensor.yaml" \
  --out "$work/calib.yaml" >/dev/null 2>&1 || fail "calibrate"
"$multislit" emulate --scenario ball --frames 8 --seconds 120 >"$work/emulate.log" 2>&1 &
emulator=$!
trap 'kill $emulator 2>/dev/null; wait $emulator 2>/dev/null' EXIT
for _ in $(seq 1 600); do  # rendering the frames first takes a few seconds
  grep -q "GigE Vision camera" "$work/emulate.log" && break
  kill -0 $emulator 2>/dev/null || fail "emulate died: $(cat "$work/emulate.log")"
  sleep 0.1
done
grep -q "GigE Vision camera" "$work/emulate.log" || fail "the emulated camera never came up"
"$multislit" map --camera 127.0.0.1 --calibration "$work/calib.yaml" --sensor \
  "$work/sim/sensor.yaml" --frames 20 --out "$work/camera" >"$work/camera.log" 2>&1 ||
  fail "map --camera: $(tail -5 "$work/camera.log")"
grep -q "20 processed" "$work/camera/summary.txt" || fail "map --camera: not 20 frames"
cam=$(occupied "$work/camera/summary.txt")
echo "map --camera 127.0.0.1: 20 frames, $cam occupied voxels"
# The camera stands still: nothing sweeps the floor, so no evidence accumulates (docs/walk.md,
# "Evidence over the sweep") and even the ball stays unknown rather than guessed.
[[ $cam -eq 0 ]] || fail "a view that never moved made $cam occupied voxels"
kill $emulator 2>/dev/null
wait $emulator 2>/dev/null

# The demo's walk rendered live; a frame not rendered in time carries the last image again.
"$multislit" emulate --walk --seconds 120 >"$work/live.log" 2>&1 &
emulator=$!
for _ in $(seq 1 600); do
  grep -q "GigE Vision camera" "$work/live.log" && break
  kill -0 $emulator 2>/dev/null || fail "emulate --walk died: $(cat "$work/live.log")"
  sleep 0.1
done
grep -q "rendered live" "$work/live.log" || fail "emulate --walk never came up: $(cat "$work/live.log")"
"$multislit" map --camera 127.0.0.1 --calibration "$work/calib.yaml" --poses gait --frames 20 \
  --out "$work/live" >"$work/live_map.log" 2>&1 || fail "map on the live walk: $(tail -5 "$work/live_map.log")"
grep -q "20 processed" "$work/live/summary.txt" || fail "map on the live walk: not 20 frames"
kill -INT $emulator 2>/dev/null
wait $emulator
rc=$?
[[ $rc == 130 ]] || fail "emulate --walk after Ctrl-C: rc $rc, not 130"
rendered=$(sed -n 's/.*; \([0-9]*\) rendered, \([0-9]*\) sent late.*/\1/p' "$work/live.log" | tail -1)
[[ -n $rendered && $rendered -ge 2 ]] || fail "emulate --walk rendered no walk: $(tail -2 "$work/live.log")"
echo "emulate --walk: $(tail -1 "$work/live.log")"
trap - EXIT

# 3. Ctrl-C: the run ends at a frame boundary, every file complete, rc 130. While it runs,
# decisions.csv grows as decisions.csv.part (for tail -f), and takes its name at the end.
"$multislit" map --simulate floor --out "$work/interrupted" >"$work/interrupted.log" 2>&1 &
mapper=$!
live=$work/interrupted/decisions.csv.part
for _ in $(seq 1 600); do
  [[ -f $live && $(wc -l <"$live") -ge 4 ]] && break
  sleep 0.1
done
[[ -f $live && ! -e $work/interrupted/decisions.csv ]] || fail "no live decisions.csv.part"
kill -INT $mapper
wait $mapper
rc=$?
[[ $rc == 130 ]] || fail "map after Ctrl-C: rc $rc, not 130: $(tail -3 "$work/interrupted.log")"
grep -q "(interrupted)" "$work/interrupted/summary.txt" || fail "no summary after Ctrl-C"
[[ -s $work/interrupted/map.bt && -s $work/interrupted/map_top.png ]] || fail "no map after Ctrl-C"
[[ $(tail -c 1 "$work/interrupted/decisions.csv" | od -An -c | tr -d ' ') == '\n' ]] ||
  fail "decisions.csv cut mid-row"
awk -F, 'NF != 19 { exit 1 }' "$work/interrupted/decisions.csv" || fail "a short row"
[[ -z $(find "$work/interrupted" -name '*.part*') ]] || fail "a temporary file was left"
echo "Ctrl-C: rc 130 after $(($(wc -l <"$work/interrupted/decisions.csv") - 1)) whole rows"

# 4. Errors.
bad="$work/bad_odometry.csv"
printf 'stamp_us,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n' >"$bad"
if "$multislit" map --sequence "$work/rec" --calibration "$work/rec/calibration.yaml" \
  --poses "$bad" --out "$work/bad" >"$work/bad.log" 2>&1; then
  fail "a repeated stamp was accepted"
fi
grep -q "bad_odometry.csv:3: stamp_us 0 repeats" "$work/bad.log" || fail "$(cat "$work/bad.log")"
if "$multislit" map --sequence "$work/rec" --out "$work/bad" >"$work/bad.log" 2>&1; then
  fail "map without --calibration was accepted"
fi
grep -q "calibration" "$work/bad.log" || fail "$(cat "$work/bad.log")"
"$multislit" map --help | grep -q -- "--camera 192.168" || fail "--help has no real-sensor example"
echo "map_command: all checks passed"
