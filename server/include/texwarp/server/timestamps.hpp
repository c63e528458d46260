// Wall-clock time for job rows and logs: milliseconds since the Unix epoch, and their RFC 3339 form in UTC
// with milliseconds ("2024-05-01T12:00:00.123Z").
#pragma once

#include <cstdint>
#include <string>

namespace texwarp::server {

std::int64_t now_ms();
std::string rfc3339_utc(std::int64_t ms);

}  // namespace texwarp::server
