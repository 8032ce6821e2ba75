// Where the objects of a scene may be (private to the simulator): the bounds that let a render
// trace objects only on the pixels they may cover and test shadows only where they may fall.
#pragma once

#include "shader.h"

#include <vector>

namespace multislit {

/// Columns (or rows) [first, last]; first > last when none.
struct ColumnSpan {
  int first = 0, last = -1;
};

/// Per image row, the sorted, merged spans of the columns whose pixel-centre rays may meet an
/// object of shader.scene (its bounding spheres, widened by a pixel).
std::vector<std::vector<ColumnSpan>> objectColumns(const Shader& shader);

/// For each object, a box of projector coordinates outside which its shadow cannot fall.
std::vector<ShadowBox> shadowBoxes(const Shader& shader);

}  // namespace multislit
