// JSON codec for job status and pages: see job_status_codec.hpp.
#include "texwarp/proto/job_status_codec.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_labels_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/problem_details_codec.hpp"

namespace texwarp::proto {
namespace {

nlohmann::json timestamp(const std::string& t) { return t.empty() ? nlohmann::json(nullptr) : nlohmann::json(t); }

std::string optional_timestamp(JsonReader& r, std::string_view key) {
  if (!r.has(key)) return {};
  const auto& v = r.at(key);
  if (v.is_null()) return {};
  if (!v.is_string())
    throw InputError(r.key_path(key), "expected a timestamp string or null, got " + json_type_name(v));
  return v.get<std::string>();
}

std::string required_string(JsonReader& r, std::string_view key) {
  const auto v = r.optional_string(key);
  if (!v) throw InputError(r.key_path(key), "required key is missing");
  return *v;
}

}  // namespace

nlohmann::json encode_job_status(const JobStatus& s) {
  const std::string self = "/v1/jobs/" + s.id;
  nlohmann::json links = {{"self", self}};
  if (s.state == JobState::kSucceeded) links["result"] = self + "/result";
  return {{"id", s.id},
          {"name", s.name},
          {"kind", to_string(s.kind)},
          {"state", to_string(s.state)},
          {"progress", s.progress},
          {"attempts", s.attempts},
          {"cancel_requested", s.cancel_requested},
          {"priority", s.priority},
          {"labels", encode_job_labels(s.labels)},
          {"node", s.node},
          {"created_at", s.created_at},
          {"started_at", timestamp(s.started_at)},
          {"finished_at", timestamp(s.finished_at)},
          {"error", s.error ? encode_problem(*s.error) : nlohmann::json(nullptr)},
          {"links", std::move(links)}};
}

JobStatus decode_job_status(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  JobStatus s;
  s.id = required_string(r, "id");
  if (auto v = r.optional_string("name")) s.name = *v;
  s.kind = parse_enum<JobKind>(required_string(r, "kind"), r.key_path("kind"));
  s.state = parse_enum<JobState>(required_string(r, "state"), r.key_path("state"));
  if (auto v = r.optional_integer("progress")) {
    if (*v < 0 || *v > 100) throw InputError(r.key_path("progress"), "expected 0 to 100");
    s.progress = static_cast<int>(*v);
  }
  if (auto v = r.optional_integer("attempts")) s.attempts = static_cast<int>(*v);
  if (auto v = r.optional_bool("cancel_requested")) s.cancel_requested = *v;
  if (auto v = r.optional_integer("priority")) {
    if (*v < kMinJobPriority || *v > kMaxJobPriority)
      throw InputError(r.key_path("priority"), "expected an integer from " + std::to_string(kMinJobPriority) + " to " +
                                                   std::to_string(kMaxJobPriority));
    s.priority = static_cast<int>(*v);
  }
  if (r.has("labels")) s.labels = decode_job_labels(r.at("labels"), r.key_path("labels"));
  if (auto v = r.optional_string("node")) s.node = *v;
  s.created_at = optional_timestamp(r, "created_at");
  s.started_at = optional_timestamp(r, "started_at");
  s.finished_at = optional_timestamp(r, "finished_at");
  if (r.has("error") && !r.at("error").is_null()) s.error = decode_problem(r.at("error"), r.key_path("error"));
  return s;
}

nlohmann::json encode_job_page(const JobPage& page) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const auto& s : page.jobs) jobs.push_back(encode_job_status(s));
  return {{"jobs", std::move(jobs)},
          {"next_cursor", page.next_cursor.empty() ? nlohmann::json(nullptr) : nlohmann::json(page.next_cursor)}};
}

JobPage decode_job_page(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  JobPage page;
  const auto& jobs = r.at("jobs");
  if (!jobs.is_array()) throw InputError(r.key_path("jobs"), "expected an array, got " + json_type_name(jobs));
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    page.jobs.push_back(decode_job_status(jobs[i], r.key_path("jobs").index(i)));
  }
  if (r.has("next_cursor") && !r.at("next_cursor").is_null()) page.next_cursor = required_string(r, "next_cursor");
  return page;
}

}  // namespace texwarp::proto
