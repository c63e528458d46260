// The body length a request header declares (Content-Length), read once for the router's 413 before any body is
// read (Beast's string body reserves the declared length as soon as its parser starts on the body) and for the
// connection's decision to discard a refused request's body.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace texwarp::server {

// The value of a Content-Length field: its decimal digits as a number; nullopt when the field is empty, holds
// anything but digits, or overflows 64 bits (Beast refuses such a header as bad_content_length).
std::optional<std::uint64_t> declared_content_length(std::string_view field);

}  // namespace texwarp::server
