// The files a command that renders reads: its file options, and --photometry where that names a
// photometry YAML rather than a preset or "random" (multislit simulate and walk).
#pragma once

#include "cli.h"
#include "common.h"
#include "output_file.h"

#include "multislit/sim/photometry.h"

#include <initializer_list>
#include <vector>

namespace multislit::apps {

/// inputsOf(args, options), and --photometry when it is a photometry file.
inline std::vector<NamedInput> inputsWithPhotometry(const cli::ArgParser& args,
                                                    std::initializer_list<const char*> options) {
  std::vector<NamedInput> inputs = inputsOf(args, options);
  if (isPhotometryFile(args.str("photometry")))
    inputs.push_back({"--photometry", args.str("photometry")});
  return inputs;
}

}  // namespace multislit::apps
