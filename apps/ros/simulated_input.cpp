#include "simulated_input.h"

#include "map_input_sim.h"

namespace multislit::ros_node {

apps::SimulatedInputOpener simulatedInput() { return apps::openSimulatedInput; }

}  // namespace multislit::ros_node
