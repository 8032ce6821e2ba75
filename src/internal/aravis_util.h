// RAII for the GObject and GError pointers of Aravis (private to the library: no public header
// names an Aravis type).
#pragma once

#include <arv.h>

#include <stdexcept>
#include <string>
#include <utility>

namespace multislit::aravis {

/// Owns one reference to a GObject; g_object_unref on destruction.
template <typename T>
class GPtr {
 public:
  GPtr() = default;
  explicit GPtr(T* object) : object_(object) {}
  GPtr(GPtr&& other) noexcept : object_(std::exchange(other.object_, nullptr)) {}
  GPtr& operator=(GPtr&& other) noexcept {
    if (this != &other) reset(std::exchange(other.object_, nullptr));
    return *this;
  }
  GPtr(const GPtr&) = delete;
  GPtr& operator=(const GPtr&) = delete;
  ~GPtr() { reset(); }

  void reset(T* object = nullptr) {
    if (object_ != nullptr) g_object_unref(object_);
    object_ = object;
  }
  T* get() const { return object_; }
  explicit operator bool() const { return object_ != nullptr; }

 private:
  T* object_ = nullptr;
};

/// A GError out-parameter that is freed on destruction.
class Error {
 public:
  Error() = default;
  Error(const Error&) = delete;
  Error& operator=(const Error&) = delete;
  ~Error() { g_clear_error(&error_); }

  GError** out() {
    g_clear_error(&error_);
    return &error_;
  }
  explicit operator bool() const { return error_ != nullptr; }
  std::string message() const { return error_ != nullptr ? error_->message : ""; }
  /// Throws std::runtime_error "<what>: <message>" when an error was set.
  void check(const std::string& what) const {
    if (error_ != nullptr) throw std::runtime_error(what + ": " + error_->message);
  }

 private:
  GError* error_ = nullptr;
};

}  // namespace multislit::aravis
