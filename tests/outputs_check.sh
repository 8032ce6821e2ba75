#!/usr/bin/env bash
# outputs_check: no output clobbers an input, and every output is whole or absent (issue 15).
#  - an output equal to an input, an output folder that is an input, or two outputs of one name:
#    refused, the input unchanged; an output that is a link, a device or a pipe: refused;
#  - a full disk (/dev/full, a file-size limit): a non-zero exit and no cut file;
#  - SIGINT in a long detect, walk or simulate: rc 130 at a frame boundary, every file whole;
#    in calibrate, table1 or bench: rc 130 and nothing written.
# Run as: bash outputs_check.sh <multislit> <work dir>
set -u
M=$1
work=$2
source "$(dirname "${BASH_SOURCE[0]}")/check_support.sh"
start_in "$work"
"$M" simulate --scenario cable --frames 2 --out s >/dev/null 2>&1 || fail "simulate"
"$M" calibrate --reference s/reference.png --out c.yaml >/dev/null 2>&1 || fail "calibrate"
cp s/frame_000001.png f.png && cp f.png f.orig.png && cp c.yaml c.orig.yaml

# 1. Inputs are never overwritten.
refused "is the input f.png" "$M" detect --calibration c.yaml --out f.png f.png
refused "is the input c.yaml" "$M" detect --calibration c.yaml --out c.yaml f.png
refused "is the input f.png" "$M" rdmap --calibration c.yaml --out ./f.png f.png
refused "is the input s/reference.png" "$M" calibrate --reference s/reference.png \
  --out s/reference.png
cmp -s f.png f.orig.png && cmp -s c.yaml c.orig.yaml || fail "an input was changed"
mkdir -p a b && cp f.png a/ && cp f.png b/
refused "would both be written to D/f.pcd" "$M" rdmap --calibration c.yaml --out D a/f.png b/f.png
[[ ! -e D/f.pcd ]] || fail "rdmap wrote D/f.pcd anyway"
# A command's input YAML in its output folder, and an output that is a link (renaming over it
# would replace the link; what it points to would stay as it was).
cp s/scene.yaml s/scene.orig.yaml
refused "is the input s/scene.yaml" "$M" simulate --scenario ball --scene s/scene.yaml --frames 1 \
  --out s
cmp -s s/scene.yaml s/scene.orig.yaml || fail "simulate rewrote its input s/scene.yaml"
refused "is the input s/sensor.yaml" "$M" walk --sensor s/sensor.yaml --frames 1 --record s --out w0
ln -s c.orig.yaml link.jsonl && ln -s /proc/self/fd/1 fd1.jsonl
refused "link.jsonl is a symbolic link" "$M" detect --calibration c.yaml --out link.jsonl f.png
refused "fd1.jsonl is a symbolic link" "$M" detect --calibration c.yaml --out fd1.jsonl f.png
refused "/dev/stdout is a symbolic link" "$M" detect --calibration c.yaml --out /dev/stdout f.png
refused "/dev/null is a device, pipe or socket" "$M" detect --calibration c.yaml --out /dev/null \
  f.png
# An output folder that is a link: its files would land wherever it points.
mkdir -p elsewhere && ln -s elsewhere outlink
refused "outlink is a symbolic link" "$M" simulate --scenario ball --frames 1 --out outlink
refused "outlink/ is a symbolic link" "$M" walk --frames 1 --out outlink/
[[ -z $(ls elsewhere) ]] || fail "an output went through the link outlink"
mkfifo fifo.jsonl
refused "fifo.jsonl is a device, pipe or socket" "$M" detect --calibration c.yaml \
  --out fifo.jsonl f.png
mkdir -p dir.jsonl
refused "dir.jsonl is a folder" "$M" detect --calibration c.yaml --out dir.jsonl f.png
[[ -L link.jsonl && -L fd1.jsonl ]] && cmp -s c.yaml c.orig.yaml || fail "a link was replaced"
# An output folder that is an input (the recording map reads, a file), or a file of one.
ls s >s.before
refused "--out s is the input s (--sequence)" "$M" map --sequence s --calibration c.yaml --out s
refused "--out ./s/ is the input s (--sequence)" "$M" map --sequence s --calibration c.yaml \
  --out ./s/
refused "--out s/scene.yaml is the input s/scene.yaml (--scene)" "$M" simulate --scenario ball \
  --scene s/scene.yaml --frames 1 --out s/scene.yaml
refused "is the input s/sensor.yaml (--sensor)" "$M" table1 --sensor s/sensor.yaml --out s/sensor.yaml
refused "is the input c.yaml (--calibration)" "$M" bench --sequence s --calibration c.yaml \
  --out c.yaml
refused "the output s is the input s (--sequence)" "$M" bench --sequence s --calibration c.yaml --out s
ls s | diff -q - s.before >/dev/null || fail "an input folder was written to: $(ls s | diff - s.before)"
cmp -s s/scene.yaml s/scene.orig.yaml && cmp -s c.yaml c.orig.yaml || fail "an input was changed"
echo "inputs: $refused_count clobbering commands refused, inputs unchanged"

# 2. A full disk is an error, and leaves nothing cut.
(trap '' XFSZ; ulimit -f 8; "$M" calibrate --reference s/reference.png --out big.yaml) \
  >out.log 2>&1 && fail "calibrate on a full disk reported success"
[[ ! -e big.yaml ]] || fail "a cut big.yaml was left"
frames=()
for _ in $(seq 1 40); do frames+=(f.png); done
(trap '' XFSZ; ulimit -f 8; "$M" detect --calibration c.yaml --raw --out big.jsonl "${frames[@]}") \
  >out.log 2>&1 && fail "detect on a full disk reported success"
[[ ! -e big.jsonl ]] || fail "a cut big.jsonl was left"
# map, simulate, walk --record and table1 on a full disk: an error, and no cut or empty file.
full() {  # full NAME COMMAND...: fails with a file-size limit of 8 kB
  local name=$1
  shift
  (trap '' XFSZ; ulimit -f 8; "$@") >"full_$name.log" 2>&1 &&
    fail "$name on a full disk reported success"
}
no_cut_files() {  # every file in the folders is whole: not empty, PNGs end with IEND
  local f
  for f in $(find "$@" -type f 2>/dev/null); do
    [[ -s $f ]] || fail "$f is empty"
    [[ $f != *.png ]] || [[ $(tail -c 8 "$f" | head -c 4) == IEND ]] || fail "$f is cut"
  done
}
full map "$M" map --sequence s --calibration c.yaml --out fm
full simulate "$M" simulate --scenario ball --frames 20 --out fs
full walk "$M" walk --frames 20 --record fr --out fw
full table1 "$M" table1 --frames 2 --out ft
no_cut_files fm fs fr fw ft
[[ ! -e ft/table1.csv || -e ft/fig12.png ]] || fail "table1: no figure, yet the table"
[[ -z $(find . -name '*.part*') ]] || fail "temporary files left: $(find . -name '*.part*')"
echo "full disk: calibrate, detect, map, simulate, walk --record and table1 fail, no cut file"

# interrupt NAME SECONDS COMMAND...: SIGINT after SECONDS; the command must exit with 130.
# A script's background command ignores SIGINT until it sets its own handler, and a loaded
# machine can take longer than SECONDS to get there (a clean-clone run under the sanitizers: the
# SIGINT was lost and detect went on to its 3000th frame, rc 0). So the SIGINT is sent again every
# 0.2 s until the command has ended (gone, or a zombie not yet waited for), for at most 2 minutes.
interrupt() {
  local name=$1 seconds=$2 tries
  shift 2
  "$@" >"$name.log" 2>&1 &
  local pid=$!
  sleep "$seconds"
  for ((tries = 0; tries < 600; tries++)); do
    kill -INT $pid 2>/dev/null || break
    sleep 0.2
    [[ -e /proc/$pid && $(awk '{print $3}' /proc/$pid/stat 2>/dev/null) != Z ]] || break
  done
  wait $pid
  local rc=$?
  [[ $rc == 130 ]] || fail "$name after SIGINT: rc $rc, not 130: $(tail -3 "$name.log")"
}
whole_lines() {  # whole_lines FILE FIELDS: every row has FIELDS commas-separated fields
  [[ -s $1 && $(tail -c 1 "$1" | od -An -c | tr -d ' ') == '\n' ]] || fail "$1 is cut or empty"
  awk -F, -v n="$2" 'NF != n { exit 1 }' "$1" || fail "$1 has a cut row"
}

# 3. SIGINT.
frames=()
for _ in $(seq 1 3000); do frames+=(f.png); done
interrupt detect 2 "$M" detect --calibration c.yaml --out d.jsonl "${frames[@]}"
[[ -e d.jsonl ]] || fail "no d.jsonl after SIGINT"
[[ ! -s d.jsonl || $(tail -c 1 d.jsonl | od -An -c | tr -d ' ') == '\n' ]] || fail "d.jsonl is cut"
grep -qv '}$' d.jsonl && fail "a JSON line is cut"
echo "detect: interrupted after $(wc -l <d.jsonl) whole lines"
interrupt walk 4 "$M" walk --synthesize --frames 100000 --out w
whole_lines w/obstacles.csv 25
grep -q "interrupted (Ctrl-C) at frame" w/summary.txt || fail "walk: no summary"
[[ -s w/map.bt && -s w/map_top.png ]] || fail "walk: no map"
echo "walk: interrupted after $(($(wc -l <w/obstacles.csv) - 1)) whole rows, summary and map"
interrupt simulate 4 "$M" simulate --scenario floor --frames 10000 --out sim
whole_lines sim/frames.csv 10
pngs=$(ls sim/frame_*.png | wc -l)
[[ $(($(wc -l <sim/frames.csv) - 1)) == "$pngs" ]] || fail "frames.csv does not list the $pngs PNGs"
whole_lines sim/odometry.csv 7
echo "simulate: interrupted after $pngs frames, frames.csv and odometry.csv whole"
interrupt table1 3 "$M" table1 --frames 1000 --out t1
[[ ! -e t1/table1.csv && ! -e t1/fig12.png ]] || fail "table1: a table of part of the frames"
interrupt bench 3 "$M" bench --frames 400 --passes 1000
# calibrate reads and averages 100 reference images (1.4 s for 60 on a quiet machine): the SIGINT comes while it reads.
references=()
for _ in $(seq 1 100); do references+=(--reference s/reference.png); done
interrupt calibrate 0.2 "$M" calibrate "${references[@]}" --out ci.yaml
grep -q "calibrate: interrupted" calibrate.log || fail "calibrate: no word of the interruption"
[[ ! -e ci.yaml && -z $(find . -name '.ci.yaml.part*') ]] || fail "calibrate wrote after SIGINT"
echo "table1, bench, calibrate: interrupted, nothing written"
# A recording killed outright (SIGKILL: no handler runs): frames.csv lists the frames whole on disk
# (the last PNG may be there without its row), and the recording replays.
"$M" walk --frames 100000 --record rk --out rkw >/dev/null 2>&1 &
pid=$!
for _ in $(seq 1 600); do [[ -e rk/frame_000004.png ]] && break; sleep 0.1; done
kill -9 "$pid"
wait "$pid" 2>/dev/null
whole_lines rk/frames.csv 4
rows=$(($(wc -l <rk/frames.csv) - 1))
pngs=$(ls rk/frame_*.png | wc -l)
((rows >= 4 && (rows == pngs || rows == pngs - 1))) || fail "killed: $rows rows for $pngs PNGs"
"$M" map --sequence rk --calibration rk/calibration.yaml --out rkm >rkm.log 2>&1 ||
  fail "the killed recording does not replay: $(tail -3 rkm.log)"
echo "walk --record: killed after $pngs frames, frames.csv lists $rows and replays"
echo "outputs_check: all checks passed"
