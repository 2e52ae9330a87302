// SPDX-License-Identifier: Apache-2.0
// sim::span: std::span under C++20, a small stand-in under C++17, so the public headers compile
// for C++17 consumers (ROS 2 Humble/Jazzy, Autoware) while C++20 code sees exactly std::span.
//
// Under C++20, sim::span<T> IS std::span<T> (an alias): the API is identical. Under C++17 it is
// a pointer and a size with the members the SIM headers and their users need (data, size,
// size_bytes, empty, [], begin/end, first, last, subspan) and the same implicit conversions from
// contiguous containers and arrays. The library's exported functions take (pointer, size) and
// its classes hold detail::Bytes, so the two spellings never meet in a symbol or a class layout;
// the span overloads are inline.
#pragma once

#include <cstddef>

#if __cplusplus >= 202002L && __has_include(<span>)
#include <span>
#endif

#if defined(__cpp_lib_span)

namespace sim {
template <typename T>
using span = std::span<T>;
using std::as_bytes;
using std::as_writable_bytes;
}  // namespace sim

#else

#include <array>
#include <iterator>
#include <type_traits>
#include <utility>

namespace sim {

template <typename T>
class span {
 public:
  using element_type = T;
  using value_type = std::remove_cv_t<T>;
  using size_type = std::size_t;
  using pointer = T*;
  using reference = T&;
  using iterator = T*;

  constexpr span() noexcept = default;
  constexpr span(T* data, std::size_t size) noexcept : data_(data), size_(size) {}
  template <std::size_t N>
  constexpr span(T (&array)[N]) noexcept : data_(array), size_(N) {}  // NOLINT: implicit as std::span
  // Any contiguous container whose elements convert (T or const T): vector, array, string, span<U>.
  template <typename Container,
            typename Element = std::remove_pointer_t<decltype(std::data(std::declval<Container&>()))>,
            typename = std::enable_if_t<!std::is_array_v<std::remove_reference_t<Container>> &&
                                        std::is_convertible_v<Element (*)[], T (*)[]>>,
            typename = decltype(std::size(std::declval<Container&>()))>
  constexpr span(Container&& container) noexcept  // NOLINT: implicit as std::span
      : data_(std::data(container)), size_(std::size(container)) {}

  constexpr T* data() const noexcept { return data_; }
  constexpr std::size_t size() const noexcept { return size_; }
  constexpr std::size_t size_bytes() const noexcept { return size_ * sizeof(T); }
  [[nodiscard]] constexpr bool empty() const noexcept { return size_ == 0; }
  constexpr T& operator[](std::size_t i) const noexcept { return data_[i]; }
  constexpr T& front() const noexcept { return data_[0]; }
  constexpr T& back() const noexcept { return data_[size_ - 1]; }
  constexpr T* begin() const noexcept { return data_; }
  constexpr T* end() const noexcept { return data_ + size_; }
  constexpr span first(std::size_t count) const noexcept { return {data_, count}; }
  constexpr span last(std::size_t count) const noexcept { return {data_ + size_ - count, count}; }
  constexpr span subspan(std::size_t offset, std::size_t count = std::size_t(-1)) const noexcept {
    return {data_ + offset, count == std::size_t(-1) ? size_ - offset : count};
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

template <typename T, std::size_t N>
span(T (&)[N]) -> span<T>;
template <typename Container>
span(Container&) -> span<std::remove_pointer_t<decltype(std::data(std::declval<Container&>()))>>;
template <typename Container>
span(const Container&) -> span<std::remove_pointer_t<decltype(std::data(std::declval<const Container&>()))>>;

template <typename T>
span<const std::byte> as_bytes(span<T> s) noexcept {
  return {reinterpret_cast<const std::byte*>(s.data()), s.size_bytes()};
}
template <typename T, typename = std::enable_if_t<!std::is_const_v<T>>>
span<std::byte> as_writable_bytes(span<T> s) noexcept {
  return {reinterpret_cast<std::byte*>(s.data()), s.size_bytes()};
}

}  // namespace sim

#endif

namespace sim::detail {

// How Borrow and Loan hold their bytes: a pointer and a size, the same type in C++17 and C++20
// translation units (a span member would be std::span in one and sim::span in the other, and
// those classes cross between the library and its users).
template <typename T>
class Bytes {
 public:
  constexpr Bytes() noexcept = default;
  constexpr Bytes(T* data, std::size_t size) noexcept : data_(data), size_(size) {}
  constexpr Bytes(span<T> s) noexcept : data_(s.data()), size_(s.size()) {}  // NOLINT: implicit
  constexpr operator span<T>() const noexcept { return {data_, size_}; }     // NOLINT: implicit
  constexpr T* data() const noexcept { return data_; }
  constexpr std::size_t size() const noexcept { return size_; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace sim::detail
