#!/usr/bin/env bash
# The passes of the slits over every floor: `multislit walk --measure-sweep` (the robot walks
# straight whatever the map holds, the ball and the cable in its path) on every named photometry
# but dark-floor (its walk reference cannot be calibrated) and on random floors, then the three
# histograms of all the walks summed (docs/walk.md, "What the passes show").
#
#   tools/sweep_floors.sh [--multislit PATH] [--out DIR] [--frames N] [--jobs N] [SEED...]
#
# SEED...: the random floors (default 1001 to 1010). Each walk's outputs stay in DIR/<floor>/;
# the summed counts go to DIR/sweep_histograms.csv and, as Markdown tables, to stdout.
set -euo pipefail

multislit=build/multislit
out=out/sweep_floors
frames=560
jobs=2
seeds=()
while (($#)); do
  case $1 in
    --multislit) multislit=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    -h | --help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "sweep_floors.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) seeds+=("$1"); shift ;;
  esac
done
((${#seeds[@]})) || seeds=(1001 1002 1003 1004 1005 1006 1007 1008 1009 1010)
[[ -x $multislit ]] || { echo "sweep_floors.sh: no multislit at $multislit (build it first)" >&2; exit 1; }
[[ $frames =~ ^[0-9]+$ ]] && ((frames > 0)) || { echo "sweep_floors.sh: --frames must be a positive integer" >&2; exit 2; }
[[ $jobs =~ ^[0-9]+$ ]] && ((jobs > 0)) || { echo "sweep_floors.sh: --jobs must be a positive integer" >&2; exit 2; }

floors=()
for p in default bright-room saturated narrow defocus speckle tiles carpet glossy 16bit gamma noisy \
  translucent-objects; do
  floors+=("$p:1")
done
for s in "${seeds[@]}"; do floors+=("random:$s"); done

mkdir -p "$out"
walk_one() {  # <photometry:seed>
  local photometry=${1%%:*} seed=${1##*:} name
  name=$photometry
  [[ $photometry == random ]] && name=random$seed
  if "$multislit" walk --measure-sweep --photometry "$photometry" --seed "$seed" --frames "$frames" \
    --out "$out/$name" >"$out/$name.log" 2>&1; then
    echo "  $name"
  else
    echo "  $name FAILED (see $out/$name.log)" >&2
    return 1
  fi
}
export -f walk_one
export multislit out frames
echo "sweep_floors.sh: ${#floors[@]} walks of $frames frames, $jobs at a time, into $out/" >&2
printf '%s\n' "${floors[@]}" | xargs -P "$jobs" -I{} bash -c 'walk_one "$@"' _ {} >&2

# The histograms of all the walks summed: counts, then each bin's share of its kind's passes.
awk -F, 'FNR == 1 { next }
  { key = $1 "," $2; if (!(key in floor)) order[n++] = key; floor[key] += $3; object[key] += $4
    all_floor[$1] += $3; all_object[$1] += $4 }
  END {
    print "histogram,bin,floor_passes,object_passes" > OUT
    for (i = 0; i < n; i++) {
      split(order[i], k, ","); h = k[1]
      print order[i] "," floor[order[i]] "," object[order[i]] > OUT
      if (h != last) {
        printf "\n%s | passes where no object lies (%d) | passes on an object (%d)\n--- | --- | ---\n", h, all_floor[h], all_object[h]
        last = h
      }
      printf "%s | %.1f %% | %.1f %%\n", k[2], all_floor[h] ? 100 * floor[order[i]] / all_floor[h] : 0,
        all_object[h] ? 100 * object[order[i]] / all_object[h] : 0
    }
  }' OUT="$out/sweep_histograms.csv" "$out"/*/sweep_histograms.csv
