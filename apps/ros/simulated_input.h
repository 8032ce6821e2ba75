// The node's ~simulate input: the simulator's (simulated_input.cpp, linking multislit_map_sim) or
// none (no_simulated_input.cpp, a build for a robot), as CMake's MULTISLIT_ROS_SIMULATOR chooses.
#pragma once

#include "map_input.h"

namespace multislit::ros_node {

/// What opens ~simulate; empty when the node was built without the simulator.
apps::SimulatedInputOpener simulatedInput();

}  // namespace multislit::ros_node
