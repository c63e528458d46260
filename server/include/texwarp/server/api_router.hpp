// ApiRouter: texwarpd's routes, declared once as data (routes()). plan() looks at a request's header only (auth
// before anything but the probes, route, content type, body limit, Idempotency-Key claim) so that refusals never
// read a body; handle() answers the whole request (or defers its answer: RequestPlan::deferred, a long poll). Both
// never throw: every error becomes an RFC 9457 problem
// (problem_types.hpp) in valid UTF-8 whatever bytes the request carried, and a 500 says only "internal error" plus
// the request id.
#pragma once

#include <functional>
#include <span>
#include <string>

#include "texwarp/server/http_types.hpp"
#include "texwarp/server/job_service.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/route.hpp"
#include "texwarp/server/server_config.hpp"

namespace texwarp::server {

class ApiRouter {
 public:
  ApiRouter(const ServerConfig& config, JobService& service, Metrics& metrics);

  // The route table, in the order 405's Allow header lists methods.
  static std::span<const Route> routes();
  // A path answered without a token (the probes), whatever the method.
  static bool is_open_path(std::string_view target);

  RequestPlan plan(const RequestHeader& header);

  // `body`: the request body for RequestPlan::Body::kMemory (empty for kFile, whose body is in plan.upload_file).
  ApiResponse handle(const RequestHeader& header, const std::string& body, RequestPlan& plan,
                     const std::string& request_id);

  // A problem response (also used by the connection code for 400/408/413/431/503 it detects itself).
  StringResponse problem(const ServiceError& error, const std::string& instance, unsigned version,
                         const std::string& request_id) const;

 private:
  ApiResponse livez(const RouteCall& call);
  ApiResponse readyz(const RouteCall& call);
  ApiResponse metrics(const RouteCall& call);
  ApiResponse openapi(const RouteCall& call);
  ApiResponse schema(const RouteCall& call);
  ApiResponse upload_blob(const RouteCall& call);
  ApiResponse get_blob(const RouteCall& call);
  ApiResponse submit_job(const RouteCall& call);
  ApiResponse submit_batch(const RouteCall& call);
  ApiResponse list_jobs(const RouteCall& call);
  ApiResponse get_job(const RouteCall& call);     // ?wait=S: a deferred answer (long poll)
  ApiResponse cancel_job(const RouteCall& call);  // never purges: 409 job-finished for a finished job
  ApiResponse delete_job(const RouteCall& call);  // cancels an unfinished job, purges a finished one
  ApiResponse get_result(const RouteCall& call);
  ApiResponse get_result_file(const RouteCall& call);
  ApiResponse list_nodes(const RouteCall& call);

  // `answer`, with every exception it throws turned into its problem response (StoreUnavailable: 503).
  ApiResponse guarded(const std::function<ApiResponse()>& answer, const std::string& instance, unsigned version,
                      const std::string& route, const std::string& request_id) const;

  // plan()'s checks after routing, each setting plan.refusal or not.
  void plan_body(const RequestHeader& header, const Route& route, RequestPlan& plan);
  void plan_idempotency_key(const RequestHeader& header, RequestPlan& plan);

  const ServerConfig& config_;
  JobService& service_;
  Metrics& metrics_;
};

// Status code of any response.
unsigned response_status(const ApiResponse& response);

}  // namespace texwarp::server
