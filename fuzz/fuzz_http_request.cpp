// libFuzzer target: bytes on a texwarpd connection. Requests are parsed as the server does (Beast: a header parser
// with the default 16 KiB header limit, a declared length over the route's body limit refused before the body, the
// header parser moved into a body parser with that limit, chunked bodies, pipelined requests), each target through
// parse_request_target, and the problem document that echoes the target
// (encoded with proto::safe_dump) must be valid UTF-8 JSON.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>

#include <boost/asio/buffer.hpp>
#include <boost/beast/core/string.hpp>
#include <boost/beast/http.hpp>
#include <nlohmann/json.hpp>

#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/server/declared_length.hpp"
#include "texwarp/server/request_target.hpp"

namespace {

namespace http = boost::beast::http;

constexpr std::uint32_t kHeaderLimit = 16U << 10;     // ServerConfig::max_header_bytes' default
constexpr std::uint64_t kJobBodyLimit = 32ULL << 20;  // POST /v1/jobs (--max-job-body-mb)
// Routes that take no body allow 64 KiB in texwarpd; scaled down here so that inputs of the fuzzer's sizes reach it
// (the parser's limit check is the same for any value).
constexpr std::uint64_t kSmallBodyLimit = 4U << 10;
constexpr int kMaxPipelined = 8;

[[noreturn]] void finding(const char* what, std::string_view text) {
  std::fprintf(stderr, "fuzz_http_request finding: %s\n%.*s\n", what, static_cast<int>(text.size()), text.data());
  std::abort();
}

bool is_unreserved(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '.' ||
         c == '_' || c == '~';
}

std::string percent_encode(std::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (is_unreserved(c)) {
      out.push_back(ch);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

// Independent check of the decoder: the segments and pairs, encoded again, parse back to themselves.
void check_target(std::string_view target, const texwarp::server::RequestTarget& parsed) {
  std::string encoded = "/";
  for (const std::string& segment : parsed.segments) {
    if (segment.empty()) finding("an empty path segment", target);
    encoded += percent_encode(segment) + "/";
  }
  if (!parsed.query.empty()) {
    encoded += "?";
    for (const auto& [key, value] : parsed.query) encoded += percent_encode(key) + "=" + percent_encode(value) + "&";
  }
  const texwarp::server::RequestTarget again = texwarp::server::parse_request_target(encoded);
  if (again.segments != parsed.segments) finding("path segments do not survive re-encoding", target);
  for (std::size_t i = 0; i < parsed.query.size(); ++i) {
    // A pair with an empty key and value ("?=") is kept; re-encoded it is "=" and kept again.
    if (i >= again.query.size() || again.query[i] != parsed.query[i]) {
      finding("query pairs do not survive re-encoding", target);
    }
  }
}

// The problem document texwarpd answers with for a request it refuses (fail_early / an unknown route).
void check_problem(std::string_view target, const texwarp::server::RequestTarget& parsed) {
  texwarp::proto::ProblemDetails problem;
  problem.type = std::string(texwarp::proto::kProblemTypePrefix) + "not-found";
  problem.title = "Not found";
  problem.status = 404;
  problem.instance = std::string(target.substr(0, target.find('?')));
  problem.detail = "no route " + texwarp::proto::utf8_prefix(target, 256);
  if (!parsed.segments.empty()) problem.detail += " (last segment \"" + parsed.segments.back() + "\")";
  if (!parsed.query.empty()) problem.path = parsed.query.front().first;
  const std::string body = texwarp::proto::safe_dump(texwarp::proto::encode_problem(problem));
  if (!texwarp::proto::is_valid_utf8(body)) finding("safe_dump(problem) is not valid UTF-8", body);
  const nlohmann::json back = nlohmann::json::parse(body, nullptr, false);
  if (back.is_discarded()) finding("safe_dump(problem) is not JSON", body);
  if (texwarp::proto::is_valid_utf8(problem.instance) && back.value("instance", std::string()) != problem.instance) {
    finding("a valid UTF-8 instance did not survive safe_dump", body);
  }
}

// One request from the front of `bytes`; returns the bytes it used, 0 when none can be parsed (error or more
// bytes needed, as the server would wait for).
std::size_t one_request(std::string_view bytes) {
  boost::beast::error_code ec;
  http::request_parser<http::empty_body> header_parser;
  header_parser.header_limit(kHeaderLimit);
  header_parser.body_limit(std::numeric_limits<std::uint64_t>::max());
  std::size_t used = 0;
  while (!header_parser.is_header_done()) {
    const std::size_t n = header_parser.put(boost::asio::buffer(bytes.data() + used, bytes.size() - used), ec);
    used += n;
    if (ec || n == 0) return 0;
  }
  const auto& header = header_parser.get();
  const std::string_view target = header.target();
  const texwarp::server::RequestTarget parsed = texwarp::server::parse_request_target(target);
  check_target(target, parsed);
  check_problem(target, parsed);
  // What the server reads from the header before routing.
  (void)boost::beast::iequals(header[http::field::expect], "100-continue");
  (void)header["X-Request-Id"];
  (void)header.keep_alive();
  (void)header.method_string();

  const bool job_post = header.method() == http::verb::post && parsed.segments.size() == 2 &&
                        parsed.segments[0] == "v1" && parsed.segments[1] == "jobs";
  const std::uint64_t limit = job_post ? kJobBodyLimit : kSmallBodyLimit;
  // The router's 413 before any body is read (api_router.cpp): Beast's string body reserves a declared length as
  // soon as its parser starts on the body, and its body limit is not checked against it first.
  const auto declared = texwarp::server::declared_content_length(header[http::field::content_length]);
  if (declared && *declared > limit) return 0;  // 413 and close
  http::request_parser<http::string_body> body_parser(std::move(header_parser));
  body_parser.body_limit(limit);
  body_parser.eager(true);
  while (!body_parser.is_done()) {
    const std::size_t n = body_parser.put(boost::asio::buffer(bytes.data() + used, bytes.size() - used), ec);
    used += n;
    if (ec == http::error::body_limit) return 0;  // 413 and close
    if (ec || n == 0) return 0;
  }
  const auto& request = body_parser.get();
  if (request.body().size() > limit) {
    finding("a body larger than its limit was accepted", request.body());
  }
  return request.keep_alive() ? used : 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  for (int i = 0; i < kMaxPipelined && !bytes.empty(); ++i) {
    const std::size_t used = one_request(bytes);
    if (used == 0) break;
    bytes.remove_prefix(used);
  }
  return 0;
}
