#pragma once
// Result<T>: a value or the reason there is none. The core never throws across its API and never
// logs (DESIGN.md 4.3); callers turn the reason into a log line or a diagnostic.

#include <optional>
#include <string>
#include <utility>

namespace gmm_localization {

template <typename T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit on purpose
  static Result failure(std::string reason) {
    Result r;
    r.error_ = std::move(reason);
    return r;
  }

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  /// The reason for a failure; empty when ok().
  const std::string& error() const { return error_; }

  T& value() & { return *value_; }
  const T& value() const& { return *value_; }
  T&& value() && { return std::move(*value_); }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() & { return *value_; }
  const T& operator*() const& { return *value_; }

 private:
  Result() = default;
  std::optional<T> value_;
  std::string error_;
};

/// A success or a reason, for operations with no value to return.
class Status {
 public:
  static Status success() { return Status(); }
  static Status failure(std::string reason) {
    Status s;
    s.error_ = std::move(reason);
    s.ok_ = false;
    return s;
  }
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const std::string& error() const { return error_; }

 private:
  bool ok_ = true;
  std::string error_;
};

}  // namespace gmm_localization
