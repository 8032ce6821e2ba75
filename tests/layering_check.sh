#!/usr/bin/env bash
# The core library (include/multislit/*.h, src/*.{h,cpp}) includes no simulator header
# (include/multislit/sim/): a robot with the real sensor links the core alone.
set -u
root=$1
hits=$(grep -n '#include "multislit/sim/' "$root"/include/multislit/*.h "$root"/src/*.h "$root"/src/*.cpp)
if [[ -n $hits ]]; then
  echo "the core includes simulator headers:"
  echo "$hits"
  exit 1
fi
echo "core: $(ls "$root"/include/multislit/*.h "$root"/src/*.cpp | wc -l) files, no simulator header"
