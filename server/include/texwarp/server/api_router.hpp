// ApiRouter: texwarpd's routes. plan() looks at a request's header only (auth before anything but the probes,
// route, content type, body limit, Idempotency-Key claim) so that refusals never read a body; handle() answers the
// whole request. Both never throw: every error becomes an RFC 9457 problem in valid UTF-8 (whatever bytes the
// request carried), and a 500 says only "internal error" plus the request id.
#pragma once

#include <string>

#include "texwarp/server/http_types.hpp"
#include "texwarp/server/job_service.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"

namespace texwarp::server {

class ApiRouter {
 public:
  ApiRouter(const ServerConfig& config, JobService& service, Metrics& metrics);

  RequestPlan plan(const RequestHeader& header);

  // `body`: the request body for RequestPlan::Body::kMemory (empty for kFile, whose body is in plan.upload_file).
  ApiResponse handle(const RequestHeader& header, const std::string& body, RequestPlan& plan,
                     const std::string& request_id);

  // A problem response (also used by the connection code for 400/408/413/431/503 it detects itself).
  StringResponse problem(const ApiError& error, const std::string& instance, unsigned version,
                         const std::string& request_id) const;

 private:
  ApiResponse dispatch(const RequestHeader& header, const std::string& body, RequestPlan& plan);

  const ServerConfig& config_;
  JobService& service_;
  Metrics& metrics_;
};

// Status code of any response.
unsigned response_status(const ApiResponse& response);

}  // namespace texwarp::server
