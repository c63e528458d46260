// HttpConnection (internal to libtexwarp_client): one keep-alive HTTP/1.1 connection over Beast, driven
// synchronously with a private io_context so that every step (connect, write, read) has a deadline and can be
// stopped from another thread. A reused
// connection the server closed meanwhile is reopened once, transparently.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <stop_token>
#include <string>
#include <utility>
#include <vector>

#include "texwarp/client/result.hpp"

namespace texwarp::client {

struct HttpRequest {
  std::string method = "GET";
  std::string target;     // "/v1/jobs"
  std::string body;       // sent when body_file is empty
  std::string body_file;  // stream the body from this file
  std::string content_type;
  std::vector<std::pair<std::string, std::string>> headers;
  std::string reply_file;  // stream a 2xx reply body into this file (else into HttpReply::body)
};

struct HttpReply {
  int status = 0;
  std::string body;                            // a 2xx reply streamed to a file has none
  std::map<std::string, std::string> headers;  // names in lower case
};

class HttpConnection {
 public:
  HttpConnection(std::string host, std::string port, std::chrono::milliseconds connect_timeout,
                 std::chrono::milliseconds request_timeout, std::string user_agent);
  ~HttpConnection();
  HttpConnection(const HttpConnection&) = delete;
  HttpConnection& operator=(const HttpConnection&) = delete;

  // One exchange. kConnection / kTimeout / kProtocol / kIo errors; any HTTP status is a reply. Once `stop` is
  // requested the exchange is abandoned (the connection closed): kStopped.
  Result<HttpReply> exchange(const HttpRequest& spec, std::stop_token stop = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace texwarp::client
