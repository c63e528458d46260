// The client suites' shared helpers: see client_test_support.hpp.
#include "client_test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <sstream>

#include "api_helpers.hpp"

namespace texwarp::testing {

client::Client client_for(const ServerProcess& server) {
  client::ClientOptions options;
  options.server = server.url();
  options.initial_backoff = std::chrono::milliseconds(20);
  return client::Client(options);
}

long requests_answered(const ServerProcess& server, std::initializer_list<std::string> labels) {
  const HttpReply metrics = http_request(server.port(), "GET", "/metrics");
  EXPECT_EQ(metrics.status, 200);
  std::istringstream lines(metrics.body);
  long total = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("texwarpd_http_requests_total{", 0) != 0) continue;
    const std::string series = line.substr(0, line.rfind(' '));
    if (std::all_of(labels.begin(), labels.end(),
                    [&](const std::string& label) { return series.find(label) != std::string::npos; })) {
      total += std::stol(line.substr(line.rfind(' ') + 1));
    }
  }
  return total;
}

}  // namespace texwarp::testing
