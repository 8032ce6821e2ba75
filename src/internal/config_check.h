// The field checks of the config structs' validate() (private to the library).
#pragma once

#include <stdexcept>
#include <string>

namespace multislit::detail {

/// check(ok, field, rule) throws std::invalid_argument("<Config>.<field> <rule>") unless ok, so
/// that every validate() names the field the user got wrong the same way.
class FieldCheck {
 public:
  explicit constexpr FieldCheck(const char* config) : config_(config) {}
  void operator()(bool ok, const std::string& field, const std::string& rule) const {
    if (!ok) throw std::invalid_argument(std::string(config_) + "." + field + " " + rule);
  }

 private:
  const char* config_;
};

/// require(ok, what, rule) throws std::invalid_argument("<what> <rule>") unless ok: checks whose
/// message names its subject itself (an element of a list, a whole struct).
inline void require(bool ok, const std::string& what, const std::string& rule) {
  if (!ok) throw std::invalid_argument(what + " " + rule);
}

}  // namespace multislit::detail
