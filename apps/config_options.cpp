#include "config_options.h"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <sstream>

namespace multislit::apps {

std::string defaultText(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

int intOption(const cli::ArgParser& args, const std::string& name) {
  return static_cast<int>(args.integer(name, INT_MIN, INT_MAX));
}

std::string optionMessage(const std::string& message, const cli::ArgParser& args,
                          const std::map<std::string, std::string>& renamed) {
  // The field is the last part of the first dotted word: "FloorDetectorConfig.min_sigma must be
  // > 0", "sensor config: mount.tilt must be in [0, 90] deg".
  std::istringstream words(message);
  std::string word;
  while (words >> word && word.find('.') == std::string::npos) {
  }
  const std::string field = word.substr(word.rfind('.') + 1);
  const auto it = renamed.find(field);
  std::string option = it != renamed.end() ? it->second : field;
  std::replace(option.begin(), option.end(), '_', '-');
  const bool named = !option.empty() && args.declares(option) && args.given(option);
  return named ? "--" + option + ": " + message : message;
}

}  // namespace multislit::apps
