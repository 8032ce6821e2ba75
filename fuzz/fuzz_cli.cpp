// Fuzz target: a command line (one argument per line of the input) parsed by the ArgParser every
// multislit command uses, every option then read as each type the commands read, and each
// argument as a JSON string (the detect command's output).
#include "fuzz_support.h"

#include "cli.h"
#include "common.h"

#include <cmath>
#include <sstream>

using namespace multislit;

namespace {

constexpr std::size_t kMaxArgs = 64;

/// Reads --name as every type: a number, a number in a range, a whole number, in a range.
void readAll(const cli::ArgParser& args, const std::string& name) {
  try {
    fuzz::expect(std::isfinite(args.number(name)), "number() finite");
  } catch (const cli::UsageError&) {
  }
  try {
    const double v = args.number(name, -0.5, 1e6);
    fuzz::expect(v >= -0.5 && v <= 1e6, "number(lo, hi) in range");
  } catch (const cli::UsageError&) {
  }
  try {
    args.integer(name);
  } catch (const cli::UsageError&) {
  }
  try {
    const long v = args.integer(name, 2, 100000);
    fuzz::expect(v >= 2 && v <= 100000, "integer(lo, hi) in range");
  } catch (const cli::UsageError&) {
  }
}

void checkJson(const std::string& s) {
  const std::string json = apps::jsonString(s);
  fuzz::expect(json.size() >= 2 && json.front() == '"' && json.back() == '"', "JSON quotes");
  for (std::size_t k = 1; k + 1 < json.size(); ++k) {
    fuzz::expect(static_cast<unsigned char>(json[k]) >= 0x20, "no control byte in JSON");
    if (json[k] == '\\')
      ++k;  // the escaped byte
    else
      fuzz::expect(json[k] != '"', "quotes escaped in JSON");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> words;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  for (std::string line; words.size() < kMaxArgs && std::getline(in, line);) words.push_back(line);
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);

  cli::ArgParser args("fuzz", "the option parser of the multislit commands");
  args.option("frames", "10", "a whole number");
  args.option("fps", "30", "a number");
  args.option("step", "", "no default");
  args.option("estimator", "gaussian", "gaussian, centroid or windowed");
  args.flag("no-noise", "a flag");
  args.repeatable("plane", "DEPTH:IMAGE, repeatable");
  args.positionals("IMAGE...", "images");
  try {
    if (!args.parse(static_cast<int>(words.size()), argv.data())) return 0;  // --help
  } catch (const cli::UsageError&) {
    return 0;
  }
  for (const char* name : {"frames", "fps", "step", "estimator"}) readAll(args, name);
  try {
    apps::parseEstimator(args.str("estimator"));
  } catch (const cli::UsageError&) {
  }
  fuzz::expect(args.list("plane").size() + args.rest().size() <= words.size(),
               "no argument made up");
  for (const std::string& w : words) checkJson(w);
  return 0;
}
