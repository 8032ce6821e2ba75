// The reference of the paper's sensor (the bare floor at the default mount, rendered), made once
// per test program: the tests that need a reference and nothing special about it share it.
#pragma once

#include "multislit/sim/rdmap_synth.h"

namespace multislit::test {

inline const Reference& defaultReference() {
  static const Reference ref = renderFloorReference(SensorConfig{}, MountConfig{});
  return ref;
}

}  // namespace multislit::test
