// A config's YAML keys in one table of {key, member}: its file is read, written and its keys
// checked from that table, so that each key is spelt once.
#pragma once

#include "multislit/lens.h"

#include "yaml_io.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace multislit {

/// A key whose value is converted by hand (an enum by name, a number written as a string):
/// read(node, key, s) reads node[key] when present, write(fs, key, s) writes key and value.
template <typename S>
struct Codec {
  void (*read)(const cv::FileNode& node, const char* key, S& s);
  void (*write)(cv::FileStorage& fs, const char* key, const S& s);
};

/// One key of a config struct S and the member that holds its value. An `unsigned` is written as
/// a real (OpenCV's integers are 32-bit signed), a list of floats only when it is not empty, a
/// 3-vector as a list of 3 numbers. A LensDistortion stands for the keys of its eight
/// coefficients (kDistortionKeys; its own key is not used), written only when one is not zero: a
/// pinhole's file stays as it was.
template <typename S>
struct Field {
  const char* key;
  std::variant<int S::*, unsigned S::*, double S::*, std::string S::*, std::vector<float> S::*,
               Eigen::Vector3d S::*, LensDistortion S::*, Codec<S>>
      member;
};

/// Reads node[key], when present, into a 3-vector; throws std::invalid_argument naming the key
/// unless it is a list of 3 numbers.
inline void readField(const cv::FileNode& node, const char* key, Eigen::Vector3d& value) {
  const cv::FileNode n = node[key];
  if (n.empty()) return;
  const auto number = [&](int i) {
    if (!n[i].isInt() && !n[i].isReal())
      throw std::invalid_argument(std::string("field '") + key + "' must be a list of 3 numbers");
    return static_cast<double>(n[i]);
  };
  if (!n.isSeq() || n.size() != 3)
    throw std::invalid_argument(std::string("field '") + key + "' must be a list of 3 numbers");
  value = Eigen::Vector3d(number(0), number(1), number(2));
}

namespace detail {

/// f(member) for a plain member pointer, or for what a Field's variant holds.
template <typename M, typename F>
void visitMember(const M& member, F&& f) {
  if constexpr (std::is_member_object_pointer_v<M>)
    f(member);
  else
    std::visit(f, member);
}

/// The type of the member a member pointer points to; void for a Codec.
template <typename M>
struct Member {
  using type = void;
};
template <typename S, typename T>
struct Member<T S::*> {
  using type = T;
};
template <typename M>
using MemberType = typename Member<M>::type;

template <typename Table>
void appendKeys(std::vector<std::string>& keys, const Table& table) {
  for (const auto& [key, member] : table)
    visitMember(member, [&, key = key](auto m) {
      if constexpr (std::is_same_v<MemberType<decltype(m)>, LensDistortion>)
        appendKeys(keys, kDistortionKeys);
      else
        keys.emplace_back(key);
    });
}

}  // namespace detail

/// Reads every key of `table` present in `node` into its member of `s` (see readField(): absent
/// keys keep their values, a value of the wrong type is an error naming the key).
template <typename Table, typename S>
void readFields(const cv::FileNode& node, const Table& table, S& s) {
  for (const auto& [key, member] : table)
    detail::visitMember(member, [&, key = key](auto m) {
      using T = detail::MemberType<decltype(m)>;
      if constexpr (std::is_same_v<decltype(m), Codec<S>>)
        m.read(node, key, s);
      else if constexpr (std::is_same_v<T, LensDistortion>)
        readFields(node, kDistortionKeys, s.*m);
      else
        readField(node, key, s.*m);
    });
}

/// Writes every key of `table` with its member's value in `s`, in the table's order.
template <typename Table, typename S>
void writeFields(cv::FileStorage& fs, const Table& table, const S& s) {
  for (const auto& [key, member] : table)
    detail::visitMember(member, [&, key = key](auto m) {
      using T = detail::MemberType<decltype(m)>;
      if constexpr (std::is_same_v<decltype(m), Codec<S>>) {
        m.write(fs, key, s);
      } else if constexpr (std::is_same_v<T, LensDistortion>) {
        if ((s.*m).any()) writeFields(fs, kDistortionKeys, s.*m);
      } else if constexpr (std::is_same_v<T, unsigned>) {
        fs << key << static_cast<double>(s.*m);
      } else if constexpr (std::is_same_v<T, std::vector<float>>) {
        if (!(s.*m).empty()) fs << key << s.*m;
      } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
        fs << key << "[:" << (s.*m).x() << (s.*m).y() << (s.*m).z() << "]";
      } else {
        fs << key << s.*m;
      }
    });
}

/// The keys of the tables, in order: the list checkKeys() takes.
template <typename... Tables>
std::vector<std::string> keysOf(const Tables&... tables) {
  std::vector<std::string> keys;
  (detail::appendKeys(keys, tables), ...);
  return keys;
}

}  // namespace multislit
