// Result<T>: a value or a ClientError, returned by every libtexwarp_client call. No exception crosses the library's
// API: value() (and * and ->) on an error, or error() on a value, is a programming error that prints the error to
// stderr and calls std::abort() (never bad_variant_access); test ok() first, or take value_or(fallback).
#pragma once

#include <cstdio>
#include <cstdlib>
#include <utility>
#include <variant>

#include "texwarp/client/client_error.hpp"

namespace texwarp::client {

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::in_place_index<0>, std::move(value)) {}            // NOLINT: implicit by design
  Result(ClientError error) : state_(std::in_place_index<1>, std::move(error)) {}  // NOLINT

  bool ok() const noexcept { return state_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  // The value; only when ok() (else: the error on stderr, then std::abort()).
  T& value() & noexcept { return *checked_value(); }
  const T& value() const& noexcept { return *checked_value(); }
  T&& value() && noexcept { return std::move(*checked_value()); }
  // The error; only when !ok() (else std::abort()).
  const ClientError& error() const noexcept {
    if (ok()) fail("libtexwarp_client: error() of a Result that holds a value");
    return *std::get_if<1>(&state_);
  }
  // The value, or `fallback` when this is an error.
  template <typename U>
  T value_or(U&& fallback) const& {
    return ok() ? *std::get_if<0>(&state_) : static_cast<T>(std::forward<U>(fallback));
  }
  template <typename U>
  T value_or(U&& fallback) && {
    return ok() ? std::move(*std::get_if<0>(&state_)) : static_cast<T>(std::forward<U>(fallback));
  }

  T& operator*() & noexcept { return value(); }
  const T& operator*() const& noexcept { return value(); }
  T* operator->() noexcept { return checked_value(); }
  const T* operator->() const noexcept { return checked_value(); }

 private:
  [[noreturn]] static void fail(const char* what, const ClientError* error = nullptr) noexcept {
    if (error) {
      std::fprintf(stderr, "%s: %s (%s)\n", what, error->message.c_str(), to_string(error->code));
    } else {
      std::fprintf(stderr, "%s\n", what);
    }
    std::abort();
  }
  T* checked_value() noexcept {
    if (!ok()) fail("libtexwarp_client: value() of a failed Result", std::get_if<1>(&state_));
    return std::get_if<0>(&state_);
  }
  const T* checked_value() const noexcept {
    if (!ok()) fail("libtexwarp_client: value() of a failed Result", std::get_if<1>(&state_));
    return std::get_if<0>(&state_);
  }

  std::variant<T, ClientError> state_;
};

}  // namespace texwarp::client
