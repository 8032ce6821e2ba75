#!/usr/bin/env bash
# The core library (include/multislit/*.h, src/*.{h,cpp}) includes no simulator header
# (include/multislit/sim/): a robot with the real sensor links the core alone. Neither do the ROS
# node (apps/ros) and the input, output and figures it shares with `multislit map`
# (multislit_map_support): only their simulated input, apps/map_input_sim.cpp, does.
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
echo "core: $(ls "$root"/include/multislit/*.h "$root"/src/*.cpp | wc -l) files, no simulator header;" \
  "the ROS node and its shared parts: ${#shared[@]} files, none"
