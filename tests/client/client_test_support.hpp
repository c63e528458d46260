// What the client suites share: a Client for a test server (short backoff), and the server's own count of the
// requests it answered, read from /metrics (texwarpd_http_requests_total), to check what a client sent.
#pragma once

#include <initializer_list>
#include <string>

#include "server_process.hpp"
#include "texwarp/client/client.hpp"

namespace texwarp::testing {

client::Client client_for(const ServerProcess& server);

// The sum of texwarpd_http_requests_total over the series whose labels contain every one of `labels`
// (e.g. {"route=\"/v1/jobs/{id}\"", "method=\"GET\""} or {"status=\"429\""}).
long requests_answered(const ServerProcess& server, std::initializer_list<std::string> labels);

}  // namespace texwarp::testing
