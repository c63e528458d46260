// StopSource and StopToken (stop_token.hpp) over a shared std::stop_source.
#include "texwarp/client/stop_token.hpp"

#include "stop_state.hpp"

namespace texwarp::client {

bool StopToken::stop_possible() const noexcept { return state_ != nullptr; }

bool StopToken::stop_requested() const noexcept { return state_ && state_->source.stop_requested(); }

StopSource::StopSource() : state_(std::make_shared<StopState>()) {}

StopToken StopSource::get_token() const noexcept { return StopToken(state_); }

bool StopSource::request_stop() noexcept { return state_->source.request_stop(); }

bool StopSource::stop_requested() const noexcept { return state_->source.stop_requested(); }

}  // namespace texwarp::client
