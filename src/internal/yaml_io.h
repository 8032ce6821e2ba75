// Small helpers around cv::FileStorage so that every config file reports errors the same way.
#pragma once

#include <opencv2/core.hpp>

#include "file_read.h"
#include "yaml_shape.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace multislit {

/// Parses the YAML `text` of file `path`; throws std::runtime_error naming the file and what it
/// is, when yamlShapeProblem() finds something in it or it is not YAML of a map.
inline cv::FileStorage openYamlText(const std::string& text, const std::string& path,
                                    const std::string& what) {
  const std::string problem = yamlShapeProblem(text);
  if (!problem.empty()) throw std::runtime_error(what + " '" + path + "': " + problem);
  cv::FileStorage fs;
  try {
    fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
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

/// Opens a YAML file for reading; throws std::runtime_error naming the file and what it is, when
/// it cannot be read or yamlShapeProblem() finds something in it.
inline cv::FileStorage openYamlForRead(const std::string& path, const std::string& what) {
  // Read once, checked, and parsed from memory: a pipe (/dev/stdin) can be read only once.
  return openYamlText(detail::readWholeFile(path, what, kMaxYamlBytes), path, what);
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
