// SPDX-License-Identifier: Apache-2.0
// Errors as values: opening a stream can fail for many reasons a caller must be told in one
// plain sentence; the hot paths (write, read) return small status enums instead of throwing.
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace sim {

enum class ErrorCode {
  invalid_name,       // the stream name breaks the naming rules
  invalid_argument,   // a capacity, layout or option that cannot work
  not_found,          // no region with that name exists
  writer_exists,      // a live writer already owns the stream
  permission_denied,  // owner, mode or a symlink made the region unsafe to use
  region_invalid,     // the region's header fails validation (corrupt, hostile, other version)
  layout_mismatch,    // the region exists with a layout or capacity the caller did not ask for
  system_error,       // an OS call failed for a reason not listed above
};

const char* to_string(ErrorCode code) noexcept;

struct [[nodiscard]] Error {
  ErrorCode code;
  std::string message;  // one sentence: what went wrong and what to do
};

// A minimal std::expected stand-in (C++23's is not available in C++20).
template <typename T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : state_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit
  Expected(Error error) : state_(std::in_place_index<1>, std::move(error)) {}  // NOLINT: implicit

  bool has_value() const noexcept { return state_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }

  T& value() & {
    assert(has_value());
    return std::get<0>(state_);
  }
  T&& value() && {
    assert(has_value());
    return std::get<0>(std::move(state_));
  }
  T& operator*() & { return value(); }
  T* operator->() { return &value(); }

  const Error& error() const {
    assert(!has_value());
    return std::get<1>(state_);
  }

 private:
  std::variant<T, Error> state_;
};

// The result of an operation that returns nothing but may fail: true on success, else error().
//   if (auto removed = sim::destroy("/old"); !removed) report(removed.error().message);
template <>
class [[nodiscard]] Expected<void> {
 public:
  Expected() = default;  // success
  Expected(Error error) : error_(std::move(error)), failed_(true) {}  // NOLINT: implicit

  bool has_value() const noexcept { return !failed_; }
  explicit operator bool() const noexcept { return has_value(); }

  const Error& error() const {
    assert(failed_);
    return error_;
  }

 private:
  Error error_{ErrorCode::system_error, {}};
  bool failed_ = false;
};

}  // namespace sim
