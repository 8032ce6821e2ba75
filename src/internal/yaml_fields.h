// A config's YAML keys in one table of {key, member}: its file is read, written and its keys
// checked from that table, so that each key is spelt once.
#pragma once

#include "multislit/lens.h"

#include "yaml_io.h"

#include <opencv2/core.hpp>

#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace multislit {

/// One key of a config struct S and the member that holds its value. An `unsigned` is written as
/// a real (OpenCV's integers are 32-bit signed), a list of floats only when it is not empty. A
/// LensDistortion stands for the keys of its eight coefficients (kDistortionKeys; its own key is
/// not used), written only when one is not zero: a pinhole's file stays as it was.
template <typename S>
struct Field {
  const char* key;
  std::variant<int S::*, unsigned S::*, double S::*, std::string S::*, std::vector<float> S::*,
               LensDistortion S::*>
      member;
};

namespace detail {

/// f(member) for a plain member pointer, or for the one a Field's variant holds.
template <typename M, typename F>
void visitMember(const M& member, F&& f) {
  if constexpr (std::is_member_object_pointer_v<M>)
    f(member);
  else
    std::visit(f, member);
}

/// The type of the member a member pointer M points to.
template <typename M>
struct Member;
template <typename S, typename T>
struct Member<T S::*> {
  using type = T;
};
template <typename M>
constexpr bool kIsDistortion = std::is_same_v<typename Member<M>::type, LensDistortion>;

}  // namespace detail

/// Reads every key of `table` present in `node` into its member of `s` (see readField(): absent
/// keys keep their values, a value of the wrong type is an error naming the key).
template <typename Table, typename S>
void readFields(const cv::FileNode& node, const Table& table, S& s) {
  for (const auto& [key, member] : table)
    detail::visitMember(member, [&, key = key](auto m) {
      if constexpr (detail::kIsDistortion<decltype(m)>)
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
      using T = typename detail::Member<decltype(m)>::type;
      if constexpr (std::is_same_v<T, LensDistortion>) {
        if ((s.*m).any()) writeFields(fs, kDistortionKeys, s.*m);
      } else if constexpr (std::is_same_v<T, unsigned>) {
        fs << key << static_cast<double>(s.*m);
      } else if constexpr (std::is_same_v<T, std::vector<float>>) {
        if (!(s.*m).empty()) fs << key << s.*m;
      } else {
        fs << key << s.*m;
      }
    });
}

namespace detail {

template <typename Table>
void appendKeys(std::vector<std::string>& keys, const Table& table) {
  for (const auto& [key, member] : table)
    visitMember(member, [&, key = key](auto m) {
      if constexpr (kIsDistortion<decltype(m)>)
        appendKeys(keys, kDistortionKeys);
      else
        keys.emplace_back(key);
    });
}

}  // namespace detail

/// The keys of the tables, in order: the list checkKeys() takes.
template <typename... Tables>
std::vector<std::string> keysOf(const Tables&... tables) {
  std::vector<std::string> keys;
  (detail::appendKeys(keys, tables), ...);
  return keys;
}

}  // namespace multislit
