#include "simulated_input.h"

namespace multislit::ros_node {

apps::SimulatedInputOpener simulatedInput() { return {}; }

}  // namespace multislit::ros_node
