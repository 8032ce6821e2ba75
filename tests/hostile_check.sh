#!/usr/bin/env bash
# hostile_check: the reproducers of the second hardening round, each a clear error naming the file,
# line or field (rc 1 or 2) where it crashed, hung or was taken wrongly before: nesting the YAML
# parser overflowed its stack on, FIFOs and pipes, poses at 1e12 m, wrapped integers, stamps and
# rows of frames.csv, calibrations whose scale no sensor has.
# Run as: bash hostile_check.sh <multislit> <work dir>
set -u
M=$1
work=$2
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
start_in "$work"
"$M" simulate --scenario ball --frames 3 --out S >/dev/null 2>&1 || fail "simulate"
"$M" calibrate --reference S/reference.png --sensor S/sensor.yaml --out c.yaml >/dev/null 2>&1 ||
  fail "calibrate"
map() { timeout 120 "$M" map --sequence "$@"; }

# A calibration whose scale no sensor has: refused at load, naming the field.
sed -E 's/cx: [^,}]*/cx: 1e308/' c.yaml >cx.yaml
sed -E 's/([{ ])f: [^,}]*/\1f: 1e-320/' c.yaml >f.yaml
sed -E 's/disparity_constant: [^,}]*/disparity_constant: 1e308/' c.yaml >dc.yaml
refused_with 1 "scale.cx must lie inside the image" map S --calibration cx.yaml --out m
refused_with 1 "scale.f must be in [1, 1e6] px" map S --calibration f.yaml --out m
refused_with 1 "scale.disparity_constant over f (the baseline)" map S --calibration dc.yaml --out m

# Nesting: block sequences 50 000 deep; 200 000 brackets after an apostrophe; both through a pipe.
{ printf '%%YAML:1.0\n---\nmount:\n  tilt: '; printf -- '- %.0s' $(seq 50000); echo 1; } >deep.yaml
refused_with 1 "line 4 begins 50001 nested collections" \
  timeout 60 "$M" simulate --sensor deep.yaml --frames 1 --out x
{ cat c.yaml; printf "camera_id: it's\nx: "; head -c 200000 /dev/zero | tr '\0' '['; echo; } \
  >apostrophe.yaml
refused_with 1 "nested 200000 brackets deep" map S --calibration apostrophe.yaml --out m
refused_with 1 "'/dev/stdin': nested 200000 brackets deep" \
  sh -c "timeout 60 '$M' map --sequence S --calibration /dev/stdin --out m <apostrophe.yaml"
timeout 120 sh -c "cat c.yaml | '$M' map --sequence S --calibration /dev/stdin --out mp" \
  >out.log 2>&1 || fail "a calibration through a pipe: $(cat out.log)"
grep -q "3 processed" out.log || fail "a calibration through a pipe: $(cat out.log)"

# A FIFO nobody writes to, as every kind of file: refused at once, not waited on for ever.
mkfifo fifo.yaml fifo.csv
refused_with 1 "'fifo.yaml' is a pipe or device that gave nothing" \
  timeout 20 "$M" simulate --sensor fifo.yaml --frames 1 --out x
refused_with 1 "'fifo.yaml' is a pipe or device that gave nothing" \
  timeout 20 "$M" simulate --scene fifo.yaml --frames 1 --out x
refused_with 1 "'fifo.yaml' is a pipe or device that gave nothing" map S --calibration fifo.yaml --out m
refused_with 1 "'fifo.csv' is a pipe or device that gave nothing" \
  map S --calibration c.yaml --poses fifo.csv --out m

# Odometry at 1e12 m (the top view spun drawing its grid).
{ head -1 S/odometry.csv; echo "33333,1e12,0,0,0,0,0"; } >far.csv
refused_with 1 "far.csv:2: x '1e12' is farther than 100000 m from the origin" \
  map S --calibration c.yaml --poses far.csv --out m

# Integers beyond 32 bits, which OpenCV wrapped (4294968592 was read as 1296).
sed -E 's/image_width: [0-9]+/image_width: 4294968592/' c.yaml >wide.yaml
refused_with 1 "'image_width: 4294968592': the integer 4294968592 is outside" \
  map S --calibration wide.yaml --out m
printf '%%YAML:1.0\n---\ntexture_seed: 4294967296\n' >seed.yaml
refused_with 1 "the integer 4294967296 is outside" \
  timeout 60 "$M" simulate --scene seed.yaml --frames 1 --out x
refused_with 2 "--slits must be a whole number in [-2147483648, 2147483647], not 4294967298" \
  "$M" calibrate --reference S/reference.png --slits 4294967298 --out r.yaml
for fps in abc nan -1 0 ''; do
  refused_with 2 "--fps must" map S --calibration c.yaml --fps "$fps" --out m
done

[[ ! -e m ]] || fail "a refused map wrote m/"

# A recording's frame that cannot be read: named, counted in summary.txt; --strict: an error.
for kind in empty rgb folder loop; do
  rm -rf "F_$kind" && cp -r S "F_$kind" && rm "F_$kind/frame_000001.png"
  case $kind in
    empty) : >"F_$kind/frame_000001.png" ;;
    rgb) printf 'P6\n2 2\n255\n%012d' 0 >"F_$kind/frame_000001.png" ;;  # three channels
    folder) mkdir "F_$kind/frame_000001.png" ;;
    loop) ln -s frame_000001.png "F_$kind/frame_000001.png" ;;
  esac
  map "F_$kind" --calibration c.yaml --out "mf_$kind" >out.log 2>&1 ||
    fail "map over a recording with a bad frame ($kind): $(cat out.log)"
  grep -q "frames that could not be read: 1" "mf_$kind/summary.txt" ||
    fail "$kind: not in summary.txt: $(cat "mf_$kind/summary.txt")"
  grep -q "frame_000001.png" "mf_$kind/summary.txt" || fail "$kind: the frame is not named"
  grep -q "2 processed" out.log || fail "$kind: $(cat out.log)"
  refused_with 1 "frame_000001.png" map "F_$kind" --calibration c.yaml --strict --out "ms_$kind"
done

# frames.csv read strictly: stamps, header, rows naming no frame of the folder.
bad_index() {  # bad_index NAME CONTENT EXPECTED
  rm -rf "R_$1" && cp -r S "R_$1" && printf '%b' "$2" >"R_$1/frames.csv"
  refused_with 1 "$3" map "R_$1" --calibration c.yaml --out m
}
head_row=$(head -1 S/frames.csv)
row() { sed -n "$(($1 + 2))p" S/frames.csv; }
swap() { row "$1" | awk -F, -v OFS=, -v c="$2" -v v="$3" '{$c = v; print}'; }
bad_index huge "$head_row\n$(swap 0 3 1e308)\n" "frames.csv:2: stamp_us '1e308' is not a whole number"
bad_index negative "$head_row\n$(swap 0 3 -5)\n" "frames.csv:2: stamp_us '-5' is not a whole number"
bad_index nan "$head_row\n$(row 0)\n$(swap 1 3 nan)\n" "frames.csv:3: stamp_us 'nan'"
bad_index header "frame,name,time\n$(row 0)\n" "frames.csv:1: the header must name the columns"
bad_index garbage "\x01\x02garbage" "frames.csv:1: the header must name the columns"
bad_index empty "" "frames.csv:1: the header must name the columns"
bad_index missing "$head_row\n$(swap 0 2 frame_999999.png)\n" \
  "frames.csv:2: file 'frame_999999.png' is missing"
bad_index dot "$head_row\n$(swap 0 2 .)\n" "frames.csv:2: file '.' is not a file name"
bad_index passwd "$head_row\n$(swap 0 2 /etc/passwd)\n" "frames.csv:2: file '/etc/passwd' is not"
# bench --sequence reads robot_x of frames.csv: a number, within 100 km.
rm -rf B && cp -r S B && sed -i '2s/^\([^,]*,[^,]*,[^,]*\),[^,]*/\1,1e400/' B/frames.csv
refused_with 1 "B/frames.csv:2: robot_x '1e400' is not a position within 100000 m" \
  "$M" bench --sequence B --calibration c.yaml --sensor S/sensor.yaml --passes 1
echo "hostile_check: $refused_count refusals, each with its message and exit code"
