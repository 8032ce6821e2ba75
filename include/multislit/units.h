// Units used across the library: angles are configured in degrees and computed in radians.
#pragma once

#include <cmath>

namespace multislit {

inline constexpr double kDeg = M_PI / 180.0;  ///< radians per degree [rad / deg]

}  // namespace multislit
