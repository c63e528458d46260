// Result<T>: a value or a ClientError, returned by every libtexwarp_client call (no exceptions cross the library's
// API, so a DCC plugin built without exception handling around it cannot be taken down by it).
#pragma once

#include <utility>
#include <variant>

#include "texwarp/client/client_error.hpp"

namespace texwarp::client {

template <typename T>
class Result {
 public:
  Result(T value) : state_(std::in_place_index<0>, std::move(value)) {}            // NOLINT: implicit by design
  Result(ClientError error) : state_(std::in_place_index<1>, std::move(error)) {}  // NOLINT

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }

  // Only when ok() / !ok() respectively.
  T& value() & { return std::get<0>(state_); }
  const T& value() const& { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  const ClientError& error() const { return std::get<1>(state_); }

  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

 private:
  std::variant<T, ClientError> state_;
};

}  // namespace texwarp::client
