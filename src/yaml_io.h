// Small helpers around cv::FileStorage so that every config file reports errors the same way.
#pragma once

#include <opencv2/core.hpp>

#include <fstream>
#include <initializer_list>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace multislit {

/// Opens a YAML file for reading; throws std::runtime_error naming the file and what it is.
inline cv::FileStorage openYamlForRead(const std::string& path, const std::string& what) {
  if (!std::ifstream(path).good())
    throw std::runtime_error(what + " '" + path + "' cannot be read");
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(what + " '" + path + "' is not valid YAML: " + e.err);
  }
  if (!fs.isOpened()) throw std::runtime_error(what + " '" + path + "' cannot be read");
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
                      std::initializer_list<const char*> known) {
  if (node.empty() || node.isNone()) return;
  const std::string at = where.empty() ? "" : where + ".";
  if (!node.isMap())
    throw std::invalid_argument((where.empty() ? std::string("the file") : "'" + where + "'") +
                                " must be a map of keys");
  std::set<std::string> seen;
  for (const cv::FileNode& entry : node) {
    const std::string key = entry.name();
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) {
      std::string list;
      for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
      throw std::invalid_argument("unknown key '" + at + key + "' (known: " + list + ")");
    }
    if (!seen.insert(key).second)
      throw std::invalid_argument("key '" + at + key + "' is given twice");
  }
}

/// Reads node[key] into value when present; throws std::invalid_argument naming the key when
/// the entry has the wrong type. Absent keys leave the default in place.
template <typename T>
void readField(const cv::FileNode& node, const char* key, T& value) {
  if (node.empty() || !node.isMap()) return;
  const cv::FileNode n = node[key];
  if (n.empty() || n.isNone()) return;
  if constexpr (std::is_arithmetic_v<T>) {
    if (!n.isInt() && !n.isReal())
      throw std::invalid_argument(std::string("field '") + key + "' must be a number");
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!n.isString())
      throw std::invalid_argument(std::string("field '") + key + "' must be a string");
  }
  n >> value;
}

}  // namespace multislit
