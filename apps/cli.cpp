#include "cli.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <sstream>

namespace multislit::cli {

ArgParser::ArgParser(std::string command, std::string summary)
    : summary_(std::move(summary)), usage_name_("multislit " + command) {}

void ArgParser::option(const std::string& name, const std::string& default_value,
                       const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{default_value, help, false};
}

void ArgParser::flag(const std::string& name, const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{"", help, true};
}

void ArgParser::repeatable(const std::string& name, const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{"", help, false, true};
}

void ArgParser::positionals(const std::string& name, const std::string& help,
                            std::size_t min_count) {
  positional_name_ = name;
  positional_help_ = help;
  positional_min_ = min_count;
}

bool ArgParser::parse(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << help();
      return false;
    }
    if (arg.rfind("--", 0) != 0 || arg.size() == 2) {
      if (positional_name_.empty()) throw UsageError("unexpected argument '" + arg + "'");
      positional_values_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2), value;
    const std::size_t eq = name.find('=');
    const bool inline_value = eq != std::string::npos;
    if (inline_value) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const auto spec = specs_.find(name);
    if (spec == specs_.end()) throw UsageError("unknown option --" + name);
    given_.insert(name);
    if (spec->second.is_flag) {
      if (inline_value) throw UsageError("--" + name + " takes no value");
      values_[name] = "1";
      continue;
    }
    if (!inline_value) {
      if (i + 1 >= argc) throw UsageError("--" + name + " needs a value");
      value = argv[++i];
    }
    if (spec->second.is_list) lists_[name].push_back(value);
    values_[name] = value;
  }
  if (positional_values_.size() < positional_min_)
    throw UsageError("expected at least " + std::to_string(positional_min_) + " " +
                     positional_name_);
  return true;
}

std::string ArgParser::str(const std::string& name) const {
  const auto v = values_.find(name);
  if (v != values_.end()) return v->second;
  const auto s = specs_.find(name);
  if (s == specs_.end()) throw std::logic_error("no option --" + name);
  return s->second.default_value;
}

namespace {
std::string shortNumber(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%g", v);
  return s;
}
}  // namespace

double ArgParser::number(const std::string& name) const {
  const std::string text = str(name);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno != 0 || !std::isfinite(v))
    throw UsageError("--" + name + " must be a finite number, not '" + text + "'");
  return v;
}

double ArgParser::number(const std::string& name, double lo, double hi) const {
  const double v = number(name);
  if (!(v >= lo && v <= hi))
    throw UsageError("--" + name + " must be in [" + shortNumber(lo) + ", " + shortNumber(hi) +
                     "], not " + str(name));
  return v;
}

long ArgParser::integer(const std::string& name, long lo, long hi) const {
  const std::string text = str(name);
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || (errno != 0 && errno != ERANGE))
    throw UsageError("--" + name + " must be a whole number, not '" + text + "'");
  if (errno == ERANGE || v < lo || v > hi)
    throw UsageError("--" + name + " must be a whole number in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "], not " + text);
  return v;
}

long ArgParser::integer(const std::string& name) const {
  return integer(name, std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
}

std::vector<std::string> ArgParser::list(const std::string& name) const {
  const auto v = lists_.find(name);
  return v == lists_.end() ? std::vector<std::string>{} : v->second;
}

bool ArgParser::has(const std::string& name) const {
  const auto v = values_.find(name);
  return v != values_.end() && !v->second.empty();
}

std::string ArgParser::help() const {
  std::ostringstream out;
  out << "usage: " << usage_name_ << " [options]"
      << (positional_name_.empty() ? "" : " " + positional_name_) << "\n\n"
      << summary_ << "\n\noptions:\n";
  // One column for the names, as wide as the widest.
  const auto nameOf = [&](const std::string& name) {
    return "  --" + name + (specs_.at(name).is_flag ? "" : " V");
  };
  std::size_t width = std::string("  --help").size();
  for (const std::string& name : order_) width = std::max(width, nameOf(name).size());
  // The text wrapped at 100 columns, its lines under each other.
  const auto line = [&](std::string left, const std::string& text) {
    left.resize(width + 2, ' ');
    std::istringstream words(text);
    std::string word, row = left;
    for (bool first = true; words >> word; first = false) {
      if (!first && row.size() + 1 + word.size() > 100) {
        out << row << "\n";
        row = std::string(width + 2, ' ') + word;
      } else {
        row += (first ? "" : " ") + word;
      }
    }
    out << row << "\n";
  };
  for (const std::string& name : order_) {
    const Spec& s = specs_.at(name);
    // The default, unless there is none or the text says it itself.
    const bool show_default =
        !s.is_flag && !s.default_value.empty() && s.help.find("(default") == std::string::npos;
    line(nameOf(name), s.help + (show_default ? " (default: " + s.default_value + ")" : ""));
  }
  line("  --help", "this text");
  if (!positional_name_.empty())
    out << "\n  " << positional_name_ << ": " << positional_help_ << "\n";
  return out.str();
}

Progress::Progress(std::size_t total, std::string label)
    : total_(total), label_(std::move(label)), enabled_(isatty(STDERR_FILENO) == 1) {}

Progress::~Progress() { finish(); }

void Progress::update(std::size_t done) {
  if (!enabled_ || total_ == 0) return;
  const int percent = static_cast<int>(100 * done / total_);
  if (percent == last_percent_) return;
  last_percent_ = percent;
  const int width = 30, filled = percent * width / 100;
  std::fprintf(stderr, "\r%s [%s%s] %3d%% (%zu/%zu)", label_.c_str(),
               std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), percent,
               done, total_);
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  if (last_percent_ >= 0) std::fprintf(stderr, "\n");
}

}  // namespace multislit::cli
