#!/usr/bin/env bash
# cli_check: values out of range on the command line and in config files are refused with a
# message naming the option or field and a non-zero exit, never a blank or silently wrong run
# (issue 15). Also: a sensor of 13 slits is simulated, walks and calibrates.
# Run as: bash cli_check.sh <multislit> <work dir>
set -u
M=$1
work=$2
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
start_in "$work"
"$M" simulate --scenario cable --frames 1 --out s >/dev/null 2>&1 || fail "simulate"
"$M" calibrate --reference s/reference.png --out c.yaml >/dev/null 2>&1 || fail "calibrate"

# simulate: the pose within SensorConfig::validate()'s ranges, named by option and field.
refused_with 2 "--tilt must be a finite number, not 'nan'" "$M" simulate --tilt nan --out x
refused_with 2 "--tilt: sensor config: mount.tilt must be in [0, 90] deg" \
  "$M" simulate --tilt 1000 --out x
refused_with 2 "--height: sensor config: mount.height must be in (0, 10) m" \
  "$M" simulate --height -1 --out x
refused_with 2 "--fps must be in [0.01, 100000], not 1e-300" "$M" simulate --fps 1e-300 --out x
refused_with 2 "--frames must be a whole number in [0, 10000000]" "$M" simulate --frames -3 --out x
refused_with 2 "--bit-depth must be a whole number in [8, 16]" "$M" simulate --bit-depth 99 --out x
[[ ! -e x ]] || fail "a refused simulate wrote x/"
# detect, walk, bench, calibrate: the ranges of the config structs' validate().
refused_with 2 "--iterations: FloorDetectorConfig.max_iterations must be in [0, 1000000]" \
  "$M" detect --calibration c.yaml --iterations 2000000000 --out d.jsonl s/frame_000000.png
refused_with 2 "--max-sigma: FloorDetectorConfig.max_sigma must be >= min_sigma" \
  "$M" detect --calibration c.yaml --max-sigma 0.1 --out d.jsonl s/frame_000000.png
refused_with 2 "--step-length: FootConfig.step_length must be in (0, 0.5) m" \
  "$M" walk --step-length 0.5 --out w
refused_with 2 "--threshold-sigmas must be a finite number" \
  "$M" detect --calibration c.yaml --threshold-sigmas inf --out d.jsonl s/frame_000000.png
refused_with 2 "--screw needs X,Y in metres" "$M" walk --screw nan,nan --out w
refused_with 2 "--screw needs X,Y in metres" "$M" walk --screw 1,2,3 --out w
refused_with 2 "unknown photometry 'sunny'; known: default," "$M" walk --photometry sunny --out w
refused_with 2 "--photometry needs rendered images" "$M" walk --photometry tiles --synthesize --out w
refused_with 2 "--frames must be a whole number in [1, 100000], not 0" "$M" bench --frames 0
refused_with 2 "--passes must be a whole number in [1, 100000]" "$M" bench --passes 0
refused_with 2 "--ahead must be a whole number in [1, 100000], not 0" "$M" emulate --walk --ahead 0
refused_with 2 "--ahead needs --walk" "$M" emulate --ahead 5
refused_with 2 "--ahead 5000: at most 1718 images of this size fit in 2 GiB" \
  "$M" emulate --walk --ahead 5000
refused_with 2 "--region-width: ReferenceConfig.region_width must be 0 (automatic)" \
  "$M" calibrate --reference s/reference.png --region-width 2 --out r.yaml
refused_with 2 "--full-scale must be in [0, 65535]" \
  "$M" calibrate --reference s/reference.png --full-scale 70000 --out r.yaml
refused_with 2 "--full-scale goes with --reference" \
  "$M" detect --calibration c.yaml --full-scale 4095 --out d.jsonl s/frame_000000.png
[[ ! -e r.yaml && ! -e d.jsonl ]] || fail "a refused command wrote its output"

# Config files: sizes capped, the limit in the message.
sed 's/width: 1296/width: 20000/' s/sensor.yaml >big_sensor.yaml
grep -q "width: 20000" big_sensor.yaml || fail "big_sensor.yaml not made"
refused_with 1 "camera.width must be in [16, 16384] px" "$M" simulate --sensor big_sensor.yaml --out x
printf '%%YAML:1.0\n---\nobjects:\n' >many.yaml
for _ in $(seq 1 1001); do echo "  - { type: sphere, radius: 0.01, centre: [0.3, 0, 0.01] }"; done \
  >>many.yaml
refused_with 1 "1001 objects, more than the limit of 1000" "$M" simulate --scene many.yaml --out x
printf '%%YAML:1.0\n---\nobjects:\n  - { type: sphere, radius: 0.02, centre: [a, b, c] }\n' >abc.yaml
refused_with 1 "'centre' must be a list of 3 numbers" "$M" simulate --scene abc.yaml --out x

# A sensor of 13 slits: the simulator's reference has 13, and walk and table1 run on it.
sed 's/slit_count: 15/slit_count: 13/' s/sensor.yaml >s13.yaml
"$M" walk --sensor s13.yaml --frames 3 --no-ball --out w13 >out.log 2>&1 || fail "walk, 13 slits: $(cat out.log)"
"$M" simulate --sensor s13.yaml --frames 1 --out s13 >/dev/null 2>&1 || fail "simulate, 13 slits"
"$M" calibrate --reference s13/reference.png --slits 13 --out c13.yaml >out.log 2>&1 ||
  fail "calibrate, 13 slits: $(cat out.log)"
grep -q "13 slits" out.log || fail "calibrate, 13 slits: $(cat out.log)"

# --version, and every command's --help: no "(default: none)", no line over 100 columns.
"$M" --version | grep -qE '^multislit [0-9]+\.[0-9]+\.[0-9]+$' || fail "--version: $("$M" --version)"
commands=$("$M" --help | awk '/^commands:/ {on = 1; next} on && NF {print $1}')
[[ -n $commands ]] || fail "multislit --help lists no command"
for c in $commands; do
  "$M" "$c" --help >help.txt 2>&1 || fail "$c --help: rc $?"
  ! grep -q "(default: none)" help.txt || fail "$c --help says (default: none)"
  ! awk 'length > 100 { exit 1 }' help.txt && fail "$c --help has a line over 100 columns"
done
echo "cli_check: $refused_count refusals, each with its message and exit code; 13 slits walk and" \
  "calibrate; --version and $(wc -w <<<"$commands") commands' help"
