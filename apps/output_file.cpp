#include "output_file.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>

#include <map>
#include <stdexcept>
#include <system_error>

namespace multislit::apps {

namespace fs = std::filesystem;

namespace {

/// The same file as `path` would be, whether it exists or not.
fs::path resolved(const fs::path& path) {
  std::error_code error;
  const fs::path p = fs::weakly_canonical(fs::absolute(path), error);
  return error ? fs::absolute(path).lexically_normal() : p;
}

std::atomic<bool> g_stop_requested{false};
extern "C" void onStopSignal(int) { g_stop_requested = true; }
using Handler = void (*)(int);
Handler g_previous_int = SIG_DFL, g_previous_term = SIG_DFL;

}  // namespace

StopSignal::StopSignal() {
  g_stop_requested = false;
  g_previous_int = std::signal(SIGINT, onStopSignal);
  g_previous_term = std::signal(SIGTERM, onStopSignal);
}

StopSignal::~StopSignal() {
  std::signal(SIGINT, g_previous_int);
  std::signal(SIGTERM, g_previous_term);
}

bool StopSignal::requested() { return g_stop_requested; }

int interruptedNothingWritten(const std::string& command) {
  std::printf("%s: interrupted (Ctrl-C or SIGTERM): nothing written\n", command.c_str());
  return kInterruptedExit;
}

OutputFile::OutputFile(fs::path path, Temporary temporary) : path_(std::move(path)) {
  const fs::path folder = path_.has_parent_path() ? path_.parent_path() : fs::path(".");
  std::error_code error;
  // Renaming over a link would replace the link, and what it points to would stay as it was.
  if (fs::is_symlink(fs::symlink_status(path_, error)))
    throw std::runtime_error("the output " + path_.string() +
                             " is a symbolic link: writing it would replace the link, not what "
                             "it points to; name that file itself");
  // A device, a pipe or a folder cannot be replaced by a file written whole.
  const fs::file_status status = fs::status(path_, error);
  if (fs::exists(status) && !fs::is_regular_file(status))
    throw std::runtime_error("the output " + path_.string() + " is " +
                             (fs::is_directory(status) ? "a folder" : "a device, pipe or socket") +
                             ", not a regular file: name a file");
  const std::string name = path_.filename().string();
  temporary_ =
      folder / (temporary == Temporary::Live ? name + ".part"
                                             : "." + name + ".part-" + std::to_string(::getpid()));
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_)
    throw std::runtime_error("cannot write " + path_.string() + " (in " + folder.string() + ")");
}

OutputFile::~OutputFile() {
  if (committed_) return;
  out_.close();
  std::error_code ignored;
  fs::remove(temporary_, ignored);
}

void OutputFile::commit() {
  if (committed_) return;
  if (out_.is_open()) {
    out_.flush();
    const bool written = static_cast<bool>(out_);
    out_.close();
    if (!written || out_.fail())
      throw std::runtime_error("could not write all of " + path_.string() + " (disk full?)");
  }
  std::error_code error;
  if (!fs::exists(temporary_, error)) throw std::runtime_error("could not write " + path_.string());
  fs::rename(temporary_, path_, error);
  if (error) throw std::runtime_error("could not write " + path_.string() + ": " + error.message());
  committed_ = true;
}

void writeOdometry(const fs::path& path, const std::vector<OdometrySample>& samples) {
  writeWhole(
      path, [&samples](const std::string& p) { saveOdometry(p, samples); },
      [](const std::string& p) { Odometry::load(p); });
}

void refuseOverwritingInputs(const fs::path& output, const std::vector<NamedInput>& inputs,
                             const std::string& output_option) {
  if (output.empty()) return;  // not asked for
  const fs::path out = resolved(output);
  for (const NamedInput& input : inputs)
    if (!input.path.empty() && resolved(input.path) == out)
      throw std::runtime_error("the output " + output.string() + " is the input " + input.path +
                               (input.option.empty() ? "" : " (" + input.option + ")") +
                               ": writing it would destroy the input; choose another " +
                               output_option);
}

void refuseOutputFolder(const fs::path& folder, const std::string& option,
                        const std::vector<std::string>& names,
                        const std::vector<NamedInput>& inputs) {
  // The folder itself, not through a link: outputs never follow a symbolic link.
  const fs::path named = folder.has_filename() ? folder : folder.parent_path();
  std::error_code ec;
  if (fs::is_symlink(named, ec))
    throw std::runtime_error(option + " " + folder.string() + " is a symbolic link (to " +
                             fs::read_symlink(named, ec).string() +
                             "): outputs never follow a link; give the folder itself");
  const fs::path out = resolved(folder);
  for (const NamedInput& input : inputs)
    if (!input.path.empty() && resolved(input.path) == out)
      throw std::runtime_error(option + " " + folder.string() + " is the input " + input.path +
                               (input.option.empty() ? "" : " (" + input.option + ")") +
                               ": the outputs would be written into an input; choose another " +
                               option);
  for (const std::string& name : names) refuseOverwritingInputs(folder / name, inputs, option);
}

void refuseSameOutputTwice(const std::vector<fs::path>& outputs,
                           const std::vector<std::string>& sources) {
  std::map<fs::path, std::size_t> seen;
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const auto [at, fresh] = seen.emplace(resolved(outputs[k]), k);
    if (!fresh)
      throw std::runtime_error(sources[at->second] + " and " + sources[k] +
                               " would both be written to " + outputs[k].string() +
                               ": give inputs of different names, or one at a time");
  }
}

}  // namespace multislit::apps
