// Command-line parsing and terminal progress for the multislit tools.
#pragma once

#include <cstddef>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace multislit::cli {

/// A mistake on the command line; main prints it with a hint to use --help.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `--name value`, `--name=value`, `--flag` and positional arguments, with generated --help.
class ArgParser {
 public:
  ArgParser(std::string command, std::string summary);
  /// The program the usage line names (default: "multislit <command>").
  void program(std::string usage_name) { usage_name_ = std::move(usage_name); }

  void option(const std::string& name, const std::string& default_value, const std::string& help);
  void flag(const std::string& name, const std::string& help);
  /// An option that may be given several times; list() returns every value in order.
  void repeatable(const std::string& name, const std::string& help);
  void positionals(const std::string& name, const std::string& help, std::size_t min_count = 0);

  /// False when --help was asked for (the help is printed to stdout). Throws UsageError.
  bool parse(int argc, char** argv);

  std::string str(const std::string& name) const;
  double number(const std::string& name) const;  ///< finite; NaN and infinity are refused
  /// A whole number that fits an `int` (the config fields it goes to): 4294967298 is refused,
  /// not wrapped to 2.
  long integer(const std::string& name) const;
  /// The same, refused with a UsageError naming the range unless lo <= value <= hi.
  double number(const std::string& name, double lo, double hi) const;
  long integer(const std::string& name, long lo, long hi) const;
  bool has(const std::string& name) const;  ///< flag given, or option given a non-empty value
  /// Whether the command declares an option or flag `name`.
  bool declares(const std::string& name) const { return specs_.count(name) > 0; }
  /// Whether the command line named the option (its default aside).
  bool given(const std::string& name) const { return given_.count(name) > 0; }
  std::vector<std::string> list(const std::string& name) const;
  const std::vector<std::string>& rest() const { return positional_values_; }
  std::string help() const;

 private:
  struct Spec {
    std::string default_value, help;
    bool is_flag = false;
    bool is_list = false;
  };
  std::string summary_, usage_name_;
  std::vector<std::string> order_;
  std::map<std::string, Spec> specs_;
  std::map<std::string, std::string> values_;
  std::set<std::string> given_;
  std::map<std::string, std::vector<std::string>> lists_;
  std::string positional_name_, positional_help_;
  std::size_t positional_min_ = 0;
  std::vector<std::string> positional_values_;
};

/// A progress bar on stderr, drawn only when stderr is a terminal.
class Progress {
 public:
  Progress(std::size_t total, std::string label);
  ~Progress();
  void update(std::size_t done);
  void finish();

 private:
  std::size_t total_;
  std::string label_;
  bool enabled_, finished_ = false;
  int last_percent_ = -1;
};

}  // namespace multislit::cli
