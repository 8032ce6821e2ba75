// Outputs of the commands, complete or absent: each is written to a temporary file beside it,
// flushed and checked, then renamed over the name asked for; an output that would overwrite an
// input, or two outputs of one name, are refused before anything is written.
#pragma once

#include "multislit/odometry.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit::apps {

/// A file written whole or not at all. Write to stream(); commit() makes it appear under its
/// name (throws std::runtime_error naming it when the disk is full or it cannot be written);
/// destroyed without commit() (an error), the temporary file goes. The constructor refuses a
/// name that is a symbolic link (renaming over it would replace the link, and writing through it
/// would write what it points to) or anything but a regular file (a device such as /dev/stdout,
/// a pipe, a folder).
class OutputFile {
 public:
  /// How the temporary file is named.
  enum class Temporary {
    Hidden,  ///< .NAME.part-PID, beside it
    Live,    ///< NAME.part, beside it: a file that grows row by row, for `tail -f NAME.part`
  };
  explicit OutputFile(std::filesystem::path path, Temporary temporary = Temporary::Hidden);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ofstream& stream() { return out_; }
  /// The temporary file, for writers that take a path (cv::imwrite, OctoMap, PCL).
  const std::filesystem::path& temporaryPath() const { return temporary_; }
  const std::filesystem::path& path() const { return path_; }
  /// Flushes, checks, closes and renames; for writers that wrote temporaryPath() themselves,
  /// only checks that it exists and renames.
  void commit();

 private:
  std::filesystem::path path_, temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes `path` whole or not at all with a writer that takes a path: `save(temporary)`, then
/// `check(temporary)` reads it back (a full disk cuts a file, and such writers do not say so),
/// then it is renamed to `path`. Throws std::runtime_error naming `path` when either fails.
template <typename Save, typename Check>
void writeWhole(const std::filesystem::path& path, Save save, Check check) {
  OutputFile file(path);
  file.stream().close();
  save(file.temporaryPath().string());
  try {
    check(file.temporaryPath().string());
  } catch (const std::exception&) {
    throw std::runtime_error("could not write all of " + path.string() + " (disk full?)");
  }
  file.commit();
}

/// The same with a writer that checks its own writes (throws when one fails).
template <typename Save>
void writeWhole(const std::filesystem::path& path, Save save) {
  writeWhole(path, save, [](const std::string&) {});
}

/// odometry.csv, whole or absent (read back before it is renamed into place).
void writeOdometry(const std::filesystem::path& path, const std::vector<OdometrySample>& samples);

/// Ends a long run at a frame boundary on SIGINT or SIGTERM: while one lives, the signals set a
/// flag that requested() reads, and the previous handlers come back when it goes. Commands then
/// write every output whole and exit with kInterruptedExit.
class StopSignal {
 public:
  StopSignal();
  ~StopSignal();
  StopSignal(const StopSignal&) = delete;
  StopSignal& operator=(const StopSignal&) = delete;
  static bool requested();
};
inline constexpr int kInterruptedExit = 130;  ///< 128 + SIGINT, as shells report it

/// For a command that writes nothing of a part of its work (a table of fewer poses, a
/// calibration of fewer images): says "COMMAND: interrupted ...: nothing written" on stdout and
/// returns kInterruptedExit.
int interruptedNothingWritten(const std::string& command);

/// An input of a command: the option that names it ("--scene"; "" for an operand) and its path
/// ("" when not given).
struct NamedInput {
  std::string option;
  std::string path;
};

/// Throws std::runtime_error when `output` (given by `output_option`) names the same file as one
/// of `inputs` (after resolving links and relative paths): writing it would destroy that input.
void refuseOverwritingInputs(const std::filesystem::path& output,
                             const std::vector<NamedInput>& inputs,
                             const std::string& output_option = "--out");

/// For an output folder (`option`: "--out", "--record") into which a command writes the files
/// `names`: throws std::runtime_error when the folder is one of `inputs` (a recording's folder,
/// a file), or when one of those files would be one of them.
void refuseOutputFolder(const std::filesystem::path& folder, const std::string& option,
                        const std::vector<std::string>& names,
                        const std::vector<NamedInput>& inputs);

/// Throws std::runtime_error when two of `outputs` are the same file (the second would silently
/// replace the first), naming both inputs they come from (`sources`, parallel to `outputs`).
void refuseSameOutputTwice(const std::vector<std::filesystem::path>& outputs,
                           const std::vector<std::string>& sources);

}  // namespace multislit::apps
