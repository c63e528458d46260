// StopSource and StopToken: a request to stop, made on one thread and seen on others (WaitOptions::stop), as
// std::stop_source and std::stop_token are in C++20; these are C++17, as the client's headers must be for the plugin
// hosts of the VFX Reference Platform.
#pragma once

#include <memory>
#include <utility>

#include "texwarp/proto/export.hpp"

namespace texwarp::client {

struct StopState;  // the state a source and its tokens share (inside the library)

// What a StopSource's get_token() hands out; copies share the source's state. A default-constructed token has no
// source: no stop is ever requested through it.
class TEXWARP_API StopToken {
 public:
  StopToken() noexcept = default;

  bool stop_possible() const noexcept;   // it came from a StopSource
  bool stop_requested() const noexcept;  // its source's request_stop() has been called

 private:
  friend class StopSource;
  friend struct StopTokenAccess;  // the library's own view of the state
  explicit StopToken(std::shared_ptr<StopState> state) noexcept : state_(std::move(state)) {}

  std::shared_ptr<StopState> state_;
};

// Owns a stop state (copies share it); request_stop() may be called from any thread, once or many times.
class TEXWARP_API StopSource {
 public:
  StopSource();

  StopToken get_token() const noexcept;
  bool request_stop() noexcept;  // true when this call made the request (false when it had been made before)
  bool stop_requested() const noexcept;

 private:
  std::shared_ptr<StopState> state_;
};

}  // namespace texwarp::client
