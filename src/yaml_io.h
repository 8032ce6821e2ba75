// Small helpers around cv::FileStorage so that every config file reports errors the same way.
#pragma once

#include <opencv2/core.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace multislit {

/// Limits on a config file, checked before OpenCV parses it: its parser recurses once per level of
/// nesting, and a file nested 200 000 brackets deep overflows the stack.
constexpr std::size_t kMaxYamlBytes = 64u << 20;  ///< [bytes]
constexpr int kMaxYamlNesting = 64;               ///< levels of [ ] and { }
constexpr std::size_t kMaxYamlIndent = 1024;      ///< leading spaces of a line (block nesting)

/// What in `text` OpenCV's YAML parser is known to fail on (fuzz/), "" when nothing. Our files
/// are one block-style map, its keys at the start of a line. Refused: a file that starts another
/// way (a key indented, a list, a flow {...}, "...", a second "---") or has a document end "..."
/// later: when the first map ends before the file does, the parser looks for a second document,
/// and one starting with '-' (not "---") makes it loop forever; and a line starting with ':' (an
/// empty key), on which it reads before its buffer.
inline std::string yamlLayoutProblem(const std::string& text) {
  // The parser reads C strings: a NUL ends a line early, and it loses its place (loops forever).
  const std::size_t nul = text.find('\0');
  if (nul != std::string::npos)
    return "line " + std::to_string(1 + std::count(text.begin(), text.begin() + nul, '\n')) +
           " holds a NUL byte: not a text file";
  constexpr const char* kSpace = " \t\r";
  bool content = false, started = false;
  std::size_t number = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    const std::string line = text.substr(at, end - at);
    at = end + 1;
    ++number;
    const std::size_t first = line.find_first_not_of(kSpace);
    if (first == std::string::npos || line[first] == '#') continue;  // blank or a comment
    const std::string where = "line " + std::to_string(number);
    if (line[first] == ':') return where + " starts with ':' (an empty key)";
    if (!content) {
      const bool dashes = line.compare(0, 3, "---") == 0;
      const std::size_t after = dashes ? line.find_first_not_of(kSpace, 3) : 0;
      const bool document_start = dashes && (after == std::string::npos || line[after] == '#');
      if (document_start && started) return where + " starts a second document (\"---\")";
      started = started || document_start;
      if (line[0] == '%' || document_start) continue;  // a directive (%YAML:1.0), "---"
      content = true;
      const auto c = static_cast<unsigned char>(line[0]);
      if (!std::isalnum(c) && c != '_')
        return where + " must be the first key of a map, at the start of the line";
    } else if (line.compare(0, 3, "...") == 0) {
      return where + " ends the document (\"...\"): a file holds one map";
    }
  }
  return "";
}

/// Throws std::runtime_error naming the file when it is larger or nested deeper than the limits,
/// or when yamlLayoutProblem() finds something.
inline void checkYamlShape(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  std::string text;
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::size_t>(std::max<std::streamoff>(0, in.tellg()));
  if (size > kMaxYamlBytes)
    throw std::runtime_error(what + " '" + path + "' is " + std::to_string(size) +
                             " bytes, more than the limit of " + std::to_string(kMaxYamlBytes));
  text.resize(size);
  in.seekg(0);
  in.read(text.data(), static_cast<std::streamsize>(size));
  int depth = 0, deepest = 0;
  std::size_t indent = 0, widest = 0;
  bool line_start = true, comment = false;
  char quote = 0;
  for (const char c : text) {
    if (c == '\n') {
      line_start = true, comment = false, indent = 0;
      continue;
    }
    if (line_start && c == ' ') widest = std::max(widest, ++indent);
    line_start = line_start && c == ' ';
    if (comment) continue;
    if (quote) {
      quote = c == quote ? 0 : quote;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#') {
      comment = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  if (deepest > kMaxYamlNesting || widest > kMaxYamlIndent)
    throw std::runtime_error(what + " '" + path + "' is nested " +
                             (deepest > kMaxYamlNesting ? std::to_string(deepest) + " brackets"
                                                        : std::to_string(widest) + " spaces") +
                             " deep, more than the limit of " + std::to_string(kMaxYamlNesting) +
                             " brackets or " + std::to_string(kMaxYamlIndent) + " spaces");
  const std::string problem = yamlLayoutProblem(text);
  if (!problem.empty()) throw std::runtime_error(what + " '" + path + "': " + problem);
}

/// Opens a YAML file for reading; throws std::runtime_error naming the file and what it is.
inline cv::FileStorage openYamlForRead(const std::string& path, const std::string& what) {
  if (!std::ifstream(path).good())
    throw std::runtime_error(what + " '" + path + "' cannot be read");
  checkYamlShape(path, what);
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(what + " '" + path + "' is not valid YAML: " + e.err);
  } catch (const std::exception& e) {
    // Some malformed files make the parser throw a standard exception instead (fuzz/: a
    // std::length_error on the empty key of "camera: {width: 1296, : 2}").
    throw std::runtime_error(what + " '" + path + "' is not valid YAML (" + e.what() + ")");
  }
  if (!fs.isOpened()) throw std::runtime_error(what + " '" + path + "' cannot be read");
  // FileStorage::operator[] asserts (throws cv::Exception) on a top level that is not a map.
  if (!fs.root().empty() && !fs.root().isMap())
    throw std::runtime_error(what + " '" + path + "' must be a map of keys");
  return fs;
}

inline cv::FileStorage openYamlForWrite(const std::string& path, const std::string& what) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!fs.isOpened()) throw std::runtime_error(what + " '" + path + "' cannot be written");
  return fs;
}

/// Throws std::invalid_argument unless `node` is absent or a map whose keys are all `known`, each
/// at most once: a misspelt key would otherwise be ignored and its default used, and of a key
/// given twice OpenCV would keep the first. `where` names the map ("camera", "" for the top).
inline void checkKeys(const cv::FileNode& node, const std::string& where,
                      const std::vector<std::string>& known) {
  if (node.empty() || node.isNone()) return;
  const std::string at = where.empty() ? "" : where + ".";
  if (!node.isMap())
    throw std::invalid_argument((where.empty() ? std::string("the file") : "'" + where + "'") +
                                " must be a map of keys");
  std::set<std::string> seen;
  for (const cv::FileNode& entry : node) {
    const std::string key = entry.name();
    bool ok = false;
    for (const std::string& k : known) ok = ok || key == k;
    if (!ok) {
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      throw std::invalid_argument("unknown key '" + at + key + "' (known: " + list + ")");
    }
    if (!seen.insert(key).second)
      throw std::invalid_argument("key '" + at + key + "' is given twice");
  }
}

inline void checkKeys(const cv::FileNode& node, const std::string& where,
                      std::initializer_list<const char*> known) {
  checkKeys(node, where, std::vector<std::string>(known.begin(), known.end()));
}

/// Reads node[key] into value when present; throws std::invalid_argument naming the key when
/// the entry has the wrong type. Absent keys leave the default in place.
template <typename T>
void readField(const cv::FileNode& node, const char* key, T& value) {
  if (node.empty() || !node.isMap()) return;
  const cv::FileNode n = node[key];
  if (n.empty() || n.isNone()) return;
  if constexpr (std::is_integral_v<T>) {
    // OpenCV rounds a real into an int and wraps a negative one into an unsigned: refuse both.
    const double v = n.isInt() || n.isReal() ? static_cast<double>(n) : 0.5;
    if (!(v == std::floor(v) && v >= static_cast<double>(std::numeric_limits<T>::lowest()) &&
          v <= static_cast<double>(std::numeric_limits<T>::max())))
      throw std::invalid_argument(std::string("field '") + key + "' must be an integer in [" +
                                  std::to_string(std::numeric_limits<T>::lowest()) + ", " +
                                  std::to_string(std::numeric_limits<T>::max()) + "]");
    value = static_cast<T>(v);
  } else {
    if constexpr (std::is_arithmetic_v<T>) {
      if (!n.isInt() && !n.isReal())
        throw std::invalid_argument(std::string("field '") + key + "' must be a number");
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (!n.isString())
        throw std::invalid_argument(std::string("field '") + key + "' must be a string");
    }
    n >> value;
  }
}

}  // namespace multislit
