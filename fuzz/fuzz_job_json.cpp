// libFuzzer target: a POST /v1/jobs body through proto::parse_json and proto::decode_job_spec. An InputError is the
// expected outcome for bad input; its message and problem document must be valid UTF-8, and a decoded job's
// canonical form must decode again to the same canonical form.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace {

// The most bytes of a user-visible message the server echoes (problem detail).
constexpr std::size_t kMaxDetailBytes = 1024;

[[noreturn]] void finding(const char* what, std::string_view text) {
  std::fprintf(stderr, "fuzz_job_json finding: %s\n%.*s\n", what, static_cast<int>(text.size()), text.data());
  std::abort();
}

// The problem document the server answers with for an InputError: it must be valid UTF-8 JSON.
void check_problem(const texwarp::InputError& error) {
  const std::string detail = texwarp::proto::utf8_prefix(error.detail(), kMaxDetailBytes);
  const std::string where = texwarp::proto::utf8_prefix(error.where().str(), kMaxDetailBytes);
  if (!texwarp::proto::is_valid_utf8(detail)) finding("utf8_prefix(detail) is not valid UTF-8", detail);
  if (!texwarp::proto::is_valid_utf8(where)) finding("utf8_prefix(where) is not valid UTF-8", where);
  const std::string message = texwarp::proto::utf8_prefix(error.what(), kMaxDetailBytes);
  if (!texwarp::proto::is_valid_utf8(message)) finding("utf8_prefix(what) is not valid UTF-8", message);
  texwarp::proto::ProblemDetails problem;
  problem.type = std::string(texwarp::proto::kProblemTypePrefix) + "invalid-job";
  problem.title = "Invalid job";
  problem.status = 422;
  problem.detail = error.detail();  // raw: safe_dump must cope with any bytes
  problem.path = error.where().without_file().str();
  problem.instance = "/v1/jobs";
  const std::string body = texwarp::proto::safe_dump(texwarp::proto::encode_problem(problem));
  if (!texwarp::proto::is_valid_utf8(body)) finding("safe_dump(problem) is not valid UTF-8", body);
  if (!nlohmann::json::accept(body)) finding("safe_dump(problem) is not JSON", body);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  nlohmann::json canonical;
  try {
    const nlohmann::json value = texwarp::proto::parse_json(text, "request body");
    const texwarp::proto::JobSpec spec = texwarp::proto::decode_job_spec(value);
    canonical = texwarp::proto::encode_job_spec(spec);
  } catch (const texwarp::InputError& error) {
    check_problem(error);
    return 0;
  }
  // Accepted: the canonical form (what the server stores) must serialise, and decode back to itself.
  const std::string stored = texwarp::proto::safe_dump(canonical);
  if (!texwarp::proto::is_valid_utf8(stored)) finding("safe_dump(canonical job) is not valid UTF-8", stored);
  try {
    const nlohmann::json again = texwarp::proto::encode_job_spec(
        texwarp::proto::decode_job_spec(texwarp::proto::parse_json(stored, "stored job")));
    if (again != canonical) finding("the canonical job does not round-trip", stored);
  } catch (const texwarp::InputError& error) {
    finding("the canonical form of an accepted job is refused", error.what());
  }
  return 0;
}
