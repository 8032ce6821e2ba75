// Which of the tracks found in a reference image are the projector's slits (private to the core).
#pragma once

#include "slit_course.h"

#include "multislit/reference.h"

#include <string>
#include <vector>

namespace multislit {

/// The config.expected_slits slits among `tracks`, ordered across the fan (down and to the
/// right). Of the tracks at least config.min_rows long, the slits are the set with the most
/// points whose neighbours lie at least half the pattern's spacing apart: a piece that speckle
/// split off a slit, or a ridge beside it, lies closer to it and is dropped. Throws naming `what`
/// when fewer long tracks are apart, or when a track as long as a slit is left that lies apart
/// from every slit (the image shows more slits than the projector casts). `dropped` receives how
/// many tracks were left out.
std::vector<Track> selectSlits(std::vector<Track> tracks, const ReferenceConfig& config,
                               const std::string& what, int* dropped);

/// "rows a-b, rows c-d, ...": the first 20 tracks' rows, for error messages.
std::string describeTracks(const std::vector<Track>& tracks);

}  // namespace multislit
