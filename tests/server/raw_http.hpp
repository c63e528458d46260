// Plain HTTP/1.1 exchanges with a server on 127.0.0.1 for the tests, byte for byte when needed (malformed requests,
// partial bodies, oversized headers), so that every refusal path can be driven exactly.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace texwarp::testing {

struct HttpReply {
  int status = 0;                              // 0: no reply (connection closed or timed out)
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;

  nlohmann::json json() const;  // the body parsed (null when it is not JSON)
  std::string header(const std::string& name) const;
};

using Headers = std::vector<std::pair<std::string, std::string>>;

// One request on a fresh connection. Content-Length is set from the body; `content_type` is sent when not empty.
HttpReply http_request(unsigned short port, const std::string& method, const std::string& target,
                       const std::string& body = {}, const Headers& headers = {},
                       const std::string& content_type = "application/json");

// Sends `bytes` as they are and reads one reply (up to timeout_s).
HttpReply raw_exchange(unsigned short port, const std::string& bytes, double timeout_s = 10.0);

// A connection kept open by the test: send parts of a request, then read the reply.
class RawConnection {
 public:
  explicit RawConnection(unsigned short port);
  ~RawConnection();
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;
  void send(const std::string& bytes);
  HttpReply read_reply(double timeout_s = 10.0);

 private:
  int fd_ = -1;
  std::string pending_;  // bytes read past the previous reply
  bool head_ = false;    // the last request was HEAD: its reply has no body
};

}  // namespace texwarp::testing
