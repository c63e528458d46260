// texwarpd's two tables against the OpenAPI document they must agree with, both ways: the problem types
// (problem_types.hpp ↔ components.x-problem-types) and the routes (ApiRouter::routes() ↔ paths: methods, access,
// request body); plus the route lookup (parameters, 404, 405's Allow) and the problem a ServiceError becomes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/server/api_router.hpp"
#include "texwarp/server/problem_types.hpp"
#include "texwarp/server/route.hpp"

namespace texwarp::server {
namespace {

nlohmann::json openapi() {
  std::ifstream in(std::filesystem::path(TEXWARP_SOURCE_DIR) / "proto" / "schema" / "openapi.json");
  return nlohmann::json::parse(in);
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

const std::set<std::string> kOperationKeys = {"get", "put", "post", "delete", "options", "head", "patch", "trace"};

TEST(ProblemTypes, OneRowPerKindWithUniqueSlugs) {
  std::set<std::string_view> slugs;
  for (const ProblemType& t : problem_types()) {
    EXPECT_TRUE(slugs.insert(t.slug).second) << "slug twice: " << t.slug;
    EXPECT_EQ(&problem_type(t.kind), &t) << t.slug;
    EXPECT_FALSE(t.title.empty()) << t.slug;
    EXPECT_TRUE(t.status == 0 || (t.status >= 400 && t.status <= 599)) << t.slug << ": " << t.status;
    EXPECT_TRUE(t.status != 0 || t.job_error) << t.slug << " is neither an HTTP answer nor a job's error";
  }
  EXPECT_EQ(problem_type(ErrorKind::kInvalidJob).slug, "invalid-job");
  EXPECT_EQ(problem_type(ErrorKind::kStorageFull).status, 507);
}

TEST(ProblemTypes, EveryTypeInTheTableIsDocumentedAsItIs) {
  const nlohmann::json documented = openapi()["components"]["x-problem-types"];
  ASSERT_TRUE(documented.is_object());
  for (const ProblemType& t : problem_types()) {
    const std::string slug(t.slug);
    ASSERT_TRUE(documented.contains(slug)) << slug << " is not in openapi.json's components.x-problem-types";
    const nlohmann::json& d = documented[slug];
    EXPECT_EQ(d.value("title", ""), t.title) << slug;
    if (t.status == 0) {
      EXPECT_FALSE(d.contains("status")) << slug << " is only a job's error";
    } else {
      EXPECT_EQ(d.value("status", 0), t.status) << slug;
    }
    EXPECT_EQ(d.value("retry_after", false), t.retry_after_s > 0) << slug;
    EXPECT_EQ(d.value("job_error", false), t.job_error) << slug;
    EXPECT_EQ(d.value("header", ""), t.header_name) << slug;
    EXPECT_FALSE(d.value("description", "").empty()) << slug;
  }
}

TEST(ProblemTypes, EveryDocumentedTypeIsInTheTable) {
  const nlohmann::json doc = openapi();
  for (const auto& [slug, d] : doc["components"]["x-problem-types"].items()) {
    bool found = false;
    for (const ProblemType& t : problem_types()) found = found || t.slug == slug;
    EXPECT_TRUE(found) << "openapi.json documents problem type " << slug << ", which texwarpd never reports";
  }
}

TEST(ProblemTypes, AServiceErrorBecomesItsKindsProblem) {
  const ServiceError full = ServiceError(ErrorKind::kQueueFull, "12 jobs waiting").retry_after(17);
  const proto::ProblemDetails p = to_problem(full, "/v1/jobs");
  EXPECT_EQ(p.type, "urn:texwarp:problem:queue-full");
  EXPECT_EQ(p.title, "Queue full");
  EXPECT_EQ(p.status, 429);
  EXPECT_EQ(p.detail, "12 jobs waiting");
  EXPECT_EQ(p.instance, "/v1/jobs");
  EXPECT_EQ(retry_after_s(full), 17);                                               // the occurrence's own
  EXPECT_EQ(retry_after_s(ServiceError(ErrorKind::kShuttingDown, "draining")), 5);  // the kind's
  EXPECT_EQ(retry_after_s(ServiceError(ErrorKind::kNotFound, "no job")), 0);        // none

  const proto::ProblemDetails invalid =
      to_problem(ServiceError(ErrorKind::kInvalidJob, "bad", "$.warp.alpha"), "/v1/jobs");
  EXPECT_EQ(invalid.status, 422);
  EXPECT_EQ(invalid.path, "$.warp.alpha");
  // A kind that only ends jobs never answers a request as itself: it would be a bug, answered as an internal error.
  const proto::ProblemDetails numerical = to_problem(ServiceError(ErrorKind::kNumericalError, "step size"), "/x");
  EXPECT_EQ(numerical.status, 500);
  EXPECT_EQ(numerical.type, "urn:texwarp:problem:internal");

  const proto::ProblemDetails job = job_problem(ErrorKind::kAttemptsExhausted, "stopped 3 times");
  EXPECT_EQ(job.type, "urn:texwarp:problem:attempts-exhausted");
  EXPECT_EQ(job.status, 0);
  EXPECT_EQ(job.instance, "");
  EXPECT_THROW(job_problem(ErrorKind::kQueueFull, "not a job's error"), std::logic_error);
}

TEST(Routes, EveryRouteIsDocumentedWithItsMethodsAccessAndBody) {
  const nlohmann::json paths = openapi()["paths"];
  for (const Route& r : ApiRouter::routes()) {
    const std::string pattern(r.pattern);
    ASSERT_TRUE(paths.contains(pattern)) << pattern << " is not in openapi.json";
    for (const http::verb m : r.methods) {
      const std::string method = lower(http::to_string(m));
      ASSERT_TRUE(paths[pattern].contains(method)) << method << " " << pattern << " is not in openapi.json";
      const nlohmann::json& op = paths[pattern][method];
      const bool open = op.contains("security") && op["security"] == nlohmann::json::parse("[{}]");
      EXPECT_EQ(open, r.access == RouteAccess::kOpen) << method << " " << pattern;
      const nlohmann::json content =
          op.contains("requestBody") ? op["requestBody"]["content"] : nlohmann::json::object();
      switch (r.body) {
        case RouteBody::kNone:
          EXPECT_FALSE(op.contains("requestBody")) << method << " " << pattern;
          break;
        case RouteBody::kJson:
          EXPECT_TRUE(content.contains("application/json")) << method << " " << pattern;
          break;
        case RouteBody::kUpload:
          EXPECT_TRUE(content.contains("application/octet-stream")) << method << " " << pattern;
          break;
      }
    }
  }
}

TEST(Routes, EveryDocumentedOperationIsARoute) {
  int operations = 0;
  const nlohmann::json doc = openapi();
  for (const auto& [pattern, item] : doc["paths"].items()) {
    for (const auto& [key, op] : item.items()) {
      if (kOperationKeys.count(key) == 0) continue;
      ++operations;
      bool found = false;
      for (const Route& r : ApiRouter::routes()) {
        if (r.pattern != pattern) continue;
        for (const http::verb m : r.methods) found = found || lower(http::to_string(m)) == key;
      }
      EXPECT_TRUE(found) << "openapi.json documents " << key << " " << pattern << ", which texwarpd does not route";
    }
  }
  EXPECT_GE(operations, 18);
}

TEST(Routes, ARequestFindsItsRowAndParameters) {
  const auto routes = ApiRouter::routes();
  const RouteLookup file = find_route(routes, http::verb::head, {"v1", "jobs", "job_abc", "files", "warped.png"});
  ASSERT_NE(file.route, nullptr);
  EXPECT_EQ(file.route->pattern, "/v1/jobs/{id}/files/{name}");
  EXPECT_EQ(file.params["id"], "job_abc");
  EXPECT_EQ(file.params["name"], "warped.png");
  EXPECT_THROW(file.params["other"], std::out_of_range);

  // One path, two rows: the method picks the row, and Allow lists the path's methods in table order.
  const RouteLookup submit = find_route(routes, http::verb::post, {"v1", "jobs"});
  ASSERT_NE(submit.route, nullptr);
  EXPECT_EQ(submit.route->body, RouteBody::kJson);
  EXPECT_TRUE(submit.route->idempotency_key);
  const RouteLookup list = find_route(routes, http::verb::get, {"v1", "jobs"});
  ASSERT_NE(list.route, nullptr);
  EXPECT_EQ(list.route->body, RouteBody::kNone);
  const RouteLookup wrong = find_route(routes, http::verb::put, {"v1", "jobs"});
  EXPECT_EQ(wrong.route, nullptr);
  ASSERT_NE(wrong.path_route, nullptr);
  EXPECT_EQ(allow_header(wrong.allowed), "POST, GET");
  EXPECT_EQ(allow_header(find_route(routes, http::verb::put, {"v1", "jobs", "job_x"}).allowed), "GET, DELETE");

  // A custom verb ends its segment: "{id}:cancel" takes what comes before ":cancel", never an empty id.
  const RouteLookup cancel = find_route(routes, http::verb::post, {"v1", "jobs", "job_x:cancel"});
  ASSERT_NE(cancel.route, nullptr);
  EXPECT_EQ(cancel.route->pattern, "/v1/jobs/{id}:cancel");
  EXPECT_EQ(cancel.params["id"], "job_x");
  EXPECT_EQ(find_route(routes, http::verb::post, {"v1", "jobs", ":cancel"}).route, nullptr);
  EXPECT_EQ(find_route(routes, http::verb::post, {"v1", "jobs", "job_x:cancelled"}).route, nullptr);
  EXPECT_EQ(find_route(routes, http::verb::post, {"v1", "jobs", "job_x"}).route, nullptr);
  const RouteLookup get_cancel = find_route(routes, http::verb::get, {"v1", "jobs", "job_x:cancel"});
  ASSERT_NE(get_cancel.route, nullptr);  // GET reads the whole segment as the id (no such job: 404)
  EXPECT_EQ(get_cancel.route->pattern, "/v1/jobs/{id}");
  EXPECT_EQ(get_cancel.params["id"], "job_x:cancel");
  EXPECT_EQ(match_pattern("/a/{id}:go", {"a", "x:go"})->operator[]("id"), "x");
  EXPECT_FALSE(match_pattern("/a/{id}:go", {"a", "x:g"}).has_value());

  EXPECT_EQ(find_route(routes, http::verb::get, {"v1", "jobs", "a", "b"}).path_route, nullptr);
  EXPECT_EQ(find_route(routes, http::verb::get, {"livez", "x"}).path_route, nullptr);
  EXPECT_EQ(find_route(routes, http::verb::get, {}).path_route, nullptr);
  EXPECT_EQ(find_route(routes, http::verb::get, {"v2", "jobs"}).path_route, nullptr);

  EXPECT_TRUE(ApiRouter::is_open_path("/readyz?verbose=1"));
  EXPECT_TRUE(ApiRouter::is_open_path("//livez"));
  EXPECT_FALSE(ApiRouter::is_open_path("/metrics"));
  EXPECT_FALSE(ApiRouter::is_open_path("/v1/jobs"));
}

}  // namespace
}  // namespace texwarp::server
