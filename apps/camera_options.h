// The options that set what a live camera is set to (`map --camera`, `record`): exposure, gain,
// pixel format and the offset of its PTP clock from UTC. Defaults and ranges are
// AravisConfig's.
#pragma once

#include "cli.h"

#include "multislit/sources.h"

namespace multislit::apps {

/// Declares --exposure, --gain, --pixel-format and --ptp-utc-offset.
void addCameraOptions(cli::ArgParser& args);

/// Throws cli::UsageError naming the first of those options given: without --camera they would
/// set nothing.
void refuseCameraOptionsWithoutCamera(const cli::ArgParser& args);

/// `config` with those options' values (its other fields kept), validated: a cli::UsageError
/// naming the option when one is out of range or not a pixel format.
AravisConfig cameraSettingsFromArgs(const cli::ArgParser& args, AravisConfig config = {});

}  // namespace multislit::apps
