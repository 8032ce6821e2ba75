// A run of one slit's points: its points on neighbouring rows, a gap of one row allowed. The
// extractor's stray runs (stray_runs.h) and an obstacle's runs and surface (obstacles.cpp,
// obstacle_surface.h) are such runs. Internal to the core library.
#pragma once

namespace multislit::detail {

/// Farthest apart two successive points of a run lie along their slit [rows, or cells of the
/// organized cloud's row]: 2, one row may be missing between them.
constexpr int kRunReach = 2;

}  // namespace multislit::detail
