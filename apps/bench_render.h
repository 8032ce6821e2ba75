// `multislit bench --render`: the simulator's render time on the walk's scenes, the renderer
// before (RenderMethod::Exhaustive) next to today's (Culled), on every core.
#pragma once

#include <string>

namespace multislit::apps {

/// Renders `frames` frames spread over the walk of `multislit walk` (its floor, ball and cable,
/// its poses) `passes` times with each method; prints the median and 99th percentile per frame,
/// where the time went and the ratio; writes the table to `csv` when not empty. Returns 0.
int benchRender(long frames, int passes, const std::string& csv);

}  // namespace multislit::apps
