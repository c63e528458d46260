// Jobs as JSON text through proto's codec, errors as values: see job_json.hpp.
#include "texwarp/client/job_json.hpp"

#include <exception>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::client {

Result<proto::JobSpec> parse_job(std::string_view json_text, const std::string& source) {
  try {
    return proto::decode_job_spec(proto::parse_json(json_text, source));
  } catch (const InputError& e) {
    ClientError error{ErrorCode::kInvalidArgument, 0, std::string("invalid job: ") + e.what(), std::nullopt,
                      std::nullopt};
    proto::ProblemDetails problem;
    problem.type = std::string(proto::kProblemTypePrefix) + "invalid-job";
    problem.title = "Invalid job";
    problem.detail = e.detail();
    if (e.where().json_path()) problem.path = e.where().json_path()->str();
    error.problem = std::move(problem);
    return error;
  } catch (const std::exception& e) {
    return ClientError{ErrorCode::kInvalidArgument, 0, "invalid job " + source + ": " + e.what(), std::nullopt,
                       std::nullopt};
  }
}

Result<std::string> job_json(const proto::JobSpec& job) {
  try {
    return proto::safe_dump(proto::encode_job_spec(job));
  } catch (const std::exception& e) {
    return ClientError{ErrorCode::kInvalidArgument, 0, std::string("job does not encode: ") + e.what(), std::nullopt,
                       std::nullopt};
  }
}

}  // namespace texwarp::client
