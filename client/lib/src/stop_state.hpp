// The state behind StopSource and StopToken (stop_token.hpp): a std::stop_source, so that the library's own C++20
// code (a wait's pauses, an exchange in flight) waits on a std::stop_token.
#pragma once

#include <stop_token>

#include "texwarp/client/stop_token.hpp"

namespace texwarp::client {

struct StopState {
  std::stop_source source;
};

struct StopTokenAccess {
  // The std::stop_token of `token`'s source; one with no stop possible for a token without a source.
  static std::stop_token std_token(const StopToken& token) {
    return token.state_ ? token.state_->source.get_token() : std::stop_token();
  }
};

}  // namespace texwarp::client
