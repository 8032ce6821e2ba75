// Options that set fields of the library's config structs. The default an option shows is the
// field's value in a default config and the range it accepts is what the config's validate()
// accepts, so the command line restates neither.
#pragma once

#include "cli.h"

#include <map>
#include <stdexcept>
#include <string>

namespace multislit::apps {

/// A field's default as an option's default text: "%g" of the value ("0.3", "35", "0.04").
std::string defaultText(double value);

/// The whole number of option `name` as an int (the type of the config fields); the range beyond
/// that is the config's to check.
int intOption(const cli::ArgParser& args, const std::string& name);

/// What validate()'s message ("FootConfig.step_length must be in (0, 0.5) m") says on the command
/// line: prefixed with the option given that sets the field ("--step-length: FootConfig..."). The
/// field is the last part of the message's first dotted word, and its option is named after it
/// with '-' for '_', unless `renamed` maps the field to its option.
std::string optionMessage(const std::string& message, const cli::ArgParser& args,
                          const std::map<std::string, std::string>& renamed = {});

/// config.validate(), its std::invalid_argument a cli::UsageError naming the option.
template <typename Config>
void validateOptions(const Config& config, const cli::ArgParser& args,
                     const std::map<std::string, std::string>& renamed = {}) {
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw cli::UsageError(optionMessage(e.what(), args, renamed));
  }
}

}  // namespace multislit::apps
