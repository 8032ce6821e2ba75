#!/usr/bin/env bash
# distortion_check: a camera whose lens distorts, from the command line. simulate renders through
# it (--distortion); calibrate warns of the slits' bend without the lens's calibration and not
# with it (--intrinsics, a ROS camera_info file) nor for a pinhole; rdmap, detect and map take
# the calibration with its lens and refuse another; bad files are refused by file and key.
# Run as: bash distortion_check.sh <multislit> <work dir>
set -u
M=$1
work=$2
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
start_in "$work"
lens=-0.03,0.005,0.0005,-0.0003,0
"$M" simulate --scenario cond5 --distortion $lens --frames 1 --out d >/dev/null 2>&1 ||
  fail "simulate --distortion"
grep -q "k1: -2.99" d/sensor.yaml || fail "sensor.yaml has no k1: $(cat d/sensor.yaml)"
"$M" simulate --scenario cond5 --frames 1 --out p >/dev/null 2>&1 || fail "simulate"
cmp -s d/reference.png p/reference.png && fail "the lens changed nothing"
# The paper's camera: f = 4 mm / 3.75 um, the principal point at the image centre.
cat >ros.yaml <<'YAML'
image_width: 1296
image_height: 964
camera_name: multislit
camera_matrix: {rows: 3, cols: 3, data: [1066.6666666666667, 0, 647.5, 0, 1066.6666666666667, 481.5, 0, 0, 1]}
distortion_model: plumb_bob
distortion_coefficients: {rows: 1, cols: 5, data: [-0.03, 0.005, 0.0005, -0.0003, 0]}
YAML

warning="is the lens distortion missing?"
"$M" calibrate --reference p/reference.png --out cp.yaml >out.log 2>&1 || fail "calibrate pinhole"
grep -qF "$warning" out.log && fail "a pinhole's slits were taken for a distorting lens's"
"$M" calibrate --reference d/reference.png --out c0.yaml >out.log 2>&1 || fail "calibrate"
grep -qF "$warning" out.log || fail "no warning without the lens's calibration: $(cat out.log)"
"$M" calibrate --reference d/reference.png --intrinsics ros.yaml --out cd.yaml >out.log 2>&1 ||
  fail "calibrate --intrinsics: $(cat out.log)"
grep -qF "$warning" out.log && fail "a warning with the lens's calibration: $(cat out.log)"
grep -q "^lens:" cd.yaml || fail "the calibration keeps no lens"

"$M" rdmap --calibration cd.yaml --intrinsics ros.yaml --out f.pcd d/frame_000000.png \
  >/dev/null 2>&1 || fail "rdmap --intrinsics"
"$M" detect --calibration cd.yaml --intrinsics ros.yaml --out d.jsonl d/frame_000000.png \
  >/dev/null 2>&1 || fail "detect --intrinsics"
"$M" map --sequence d --calibration cd.yaml --intrinsics ros.yaml --out m >/dev/null 2>&1 ||
  fail "map --intrinsics"
refused "was made for a lens without distortion, not the camera's" \
  "$M" rdmap --calibration cp.yaml --intrinsics ros.yaml --out g.pcd d/frame_000000.png
refused "was made for a lens without distortion, not the camera's" \
  "$M" map --sequence d --calibration cp.yaml --intrinsics ros.yaml --out m2
sed 's/image_width: 1296/image_width: 640/' ros.yaml >small.yaml
refused "intrinsics '$PWD/small.yaml': image_width x image_height is 640x964" \
  "$M" detect --calibration cd.yaml --intrinsics "$PWD/small.yaml" --out e.jsonl \
  d/frame_000000.png
sed 's/plumb_bob/fisheye/' ros.yaml >fisheye.yaml
refused "'distortion_model' must be plumb_bob or rational_polynomial" \
  "$M" calibrate --reference d/reference.png --intrinsics fisheye.yaml --out x.yaml
refused_with 2 "--distortion must hold 4, 5, 8, 12 or 14 numbers" \
  "$M" simulate --distortion 0.1,0.2 --out x
refused_with 2 "--distortion takes numbers separated by commas" \
  "$M" simulate --distortion 0.1,,0,0 --out x
refused_with 2 "camera.k1 to k6 fold the image" "$M" simulate --distortion -0.9,0,0,0 --out x
[[ ! -e x && ! -e x.yaml && ! -e g.pcd && ! -e e.jsonl ]] || fail "a refused command wrote"
echo "distortion_check: ok ($refused_count refusals)"
