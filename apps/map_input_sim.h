// The simulated input of `multislit map` and the ROS node (~simulate): the simulator filming a
// scenario, behind its own target (multislit_map_sim) so that the rest of their input needs the
// core library only.
#pragma once

#include "map_input.h"

namespace multislit::apps {

/// The simulator filming options.simulate into `in`: its source, the reference of its bare floor
/// (unless a calibration was given), the scenario's mount and motion. openMapInput's
/// SimulatedInputOpener.
MapInput openSimulatedInput(const MapInputOptions& options, MapInput in);

}  // namespace multislit::apps
