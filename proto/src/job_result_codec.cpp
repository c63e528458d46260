// JSON codec for job results: see job_result_codec.hpp.
#include "texwarp/proto/job_result_codec.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {
namespace {

std::string required_string(JsonReader& r, std::string_view key) {
  const auto v = r.optional_string(key);
  if (!v) throw InputError(r.key_path(key), "required key is missing");
  return *v;
}

}  // namespace

nlohmann::json encode_job_result(const JobResult& result) {
  nlohmann::json files = nlohmann::json::array();
  for (const auto& f : result.files) {
    nlohmann::json file = {{"name", f.name},
                           {"media_type", f.media_type},
                           {"bytes", f.bytes},
                           {"sha256", f.sha256},
                           {"href", f.href}};
    if (f.role) file["role"] = to_string(*f.role);
    files.push_back(std::move(file));
  }
  return {{"job_id", result.job_id},
          {"kind", to_string(result.kind)},
          {"files", std::move(files)},
          {"report", nlohmann::json::parse(result.report_json)}};
}

JobResult decode_job_result(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  JobResult result;
  result.job_id = required_string(r, "job_id");
  result.kind = parse_enum<JobKind>(required_string(r, "kind"), r.key_path("kind"));
  const auto& files = r.at("files");
  const JsonPath files_path = r.key_path("files");
  if (!files.is_array()) throw InputError(files_path, "expected an array, got " + json_type_name(files));
  for (std::size_t i = 0; i < files.size(); ++i) {
    JsonReader f(files[i], files_path.index(i));
    ResultFile file;
    file.name = required_string(f, "name");
    if (auto v = f.optional_string("media_type")) file.media_type = *v;
    const auto bytes = f.optional_integer("bytes");
    if (!bytes || *bytes < 0) throw InputError(f.key_path("bytes"), "expected a non-negative integer");
    file.bytes = static_cast<std::uint64_t>(*bytes);
    if (auto v = f.optional_string("sha256")) file.sha256 = *v;
    file.href = required_string(f, "href");
    if (auto v = f.optional_string("role")) file.role = parse_enum<ImageRole>(*v, f.key_path("role"));
    result.files.push_back(std::move(file));
  }
  if (r.has("report")) {
    const auto& report = r.at("report");
    if (!report.is_object())
      throw InputError(r.key_path("report"), "expected an object, got " + json_type_name(report));
    result.report_json = report.dump();
  }
  return result;
}

}  // namespace texwarp::proto
