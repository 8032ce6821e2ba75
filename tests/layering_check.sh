#!/usr/bin/env bash
# The core library (include/multislit/*.h, src/*.{h,cpp}) includes no simulator header
# (include/multislit/sim/): a robot with the real sensor links the core alone. Neither do the ROS
# node (apps/ros) and the input, output and figures it shares with `multislit map`
# (multislit_map_support): only their simulated input, apps/map_input_sim.cpp, does. The simulator
# includes of the core only its public headers and the shared helpers of src/internal.
set -u
root=$1
hits=$(grep -n '#include "multislit/sim/' "$root"/include/multislit/*.h "$root"/src/*.h "$root"/src/*.cpp)
if [[ -n $hits ]]; then
  echo "the core includes simulator headers:"
  echo "$hits"
  exit 1
fi
shared=("$root"/apps/ros/*.h "$root"/apps/ros/*.cpp "$root"/apps/map_input.h
  "$root"/apps/map_input.cpp "$root"/apps/map_input_sim.h "$root"/apps/map_outputs.h
  "$root"/apps/map_outputs.cpp "$root"/apps/walk_figures.h "$root"/apps/walk_figures.cpp
  "$root"/apps/plot.h "$root"/apps/plot.cpp "$root"/apps/draw.h "$root"/apps/draw.cpp
  "$root"/apps/cli.h "$root"/apps/cli.cpp "$root"/apps/common.h "$root"/apps/common.cpp
  "$root"/apps/config_options.h "$root"/apps/config_options.cpp "$root"/apps/output_file.h
  "$root"/apps/output_file.cpp)
hits=$(grep -n '#include "multislit/sim/' "${shared[@]}")
if [[ -n $hits ]]; then
  echo "the ROS node or what it shares with multislit map includes simulator headers:"
  echo "$hits"
  exit 1
fi
# The simulator (src/sim, include/multislit/sim) uses the core through its public headers
# (multislit/...) and the helpers of src/internal only, besides its own files; no public header
# includes an internal one (they are not installed).
bad=""
for file in "$root"/src/sim/*.h "$root"/src/sim/*.cpp "$root"/include/multislit/sim/*.h; do
  while IFS= read -r line; do
    path=$(sed -E 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]([^>"]*)[>"].*/\1/' <<<"$line")
    if [[ $path != *..* ]]; then
      [[ $path == multislit/* && -f $root/include/$path ]] && continue
      [[ $file == */src/sim/* && ( -f $root/src/sim/$path || -f $root/src/internal/$path ) ]] &&
        continue
      # A system or third-party header: <...> naming no file of src/.
      [[ $line != *\"* && ! -e $root/src/$path ]] && continue
    fi
    bad+="$file: $line"$'\n'
  done < <(grep -E '^[[:space:]]*#[[:space:]]*include' "$file")
done
for internal in "$root"/src/internal/*.h; do
  hits=$(grep -n "#include [\"<]$(basename "$internal")" "$root"/include/multislit/*.h \
    "$root"/include/multislit/sim/*.h)
  [[ -n $hits ]] && bad+="$hits"$'\n'
done
if [[ -n $bad ]]; then
  echo "the simulator includes private core headers, or a public header an internal one:"
  echo -n "$bad"
  exit 1
fi
echo "core: $(ls "$root"/include/multislit/*.h "$root"/src/*.cpp | wc -l) files, no simulator header;" \
  "the ROS node and its shared parts: ${#shared[@]} files, none;" \
  "the simulator: $(ls "$root"/src/sim/* "$root"/include/multislit/sim/*.h | wc -l) files, public" \
  "and src/internal headers only"
