// A program against the installed libtexwarp_client (public headers only, every one of the client's; C++17 or
// later): checks the server is ready, parses a job file, uploads its image, runs it with progress, and prints what
// it got for the test to check: "cplusplus N" (the standard it was compiled as), "file NAME BYTES SHA256" per result
// file, "job JOB_ID", "max_px X" and "bad_job_path PATH".
// Usage: texwarp_consumer SERVER_URL JOB.json OUT_DIR
#include <cstdio>
#include <fstream>
#include <sstream>

#include "texwarp/client/client.hpp"
#include "texwarp/client/client_error.hpp"
#include "texwarp/client/job_json.hpp"
#include "texwarp/client/result.hpp"
#include "texwarp/client/stop_token.hpp"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s SERVER_URL JOB.json OUT_DIR\n", argv[0]);
    return 2;
  }
  std::printf("cplusplus %ld\n", static_cast<long>(__cplusplus));
  namespace tc = texwarp::client;
  tc::ClientOptions options;
  options.server = argv[1];
  tc::Client client(options);
  const auto ready = client.ready();
  if (!ready) {
    std::fprintf(stderr, "not reachable: %s\n", ready.error().message.c_str());
    return 1;
  }
  std::ifstream in(argv[2]);
  std::stringstream text;
  text << in.rdbuf();
  auto job = tc::parse_job(text.str(), argv[2]);
  if (!job) {
    std::fprintf(stderr, "%s\n", job.error().message.c_str());
    return 2;
  }
  if (job->image.kind == texwarp::proto::ImageSourceSpec::Kind::kPath) {
    const auto blob = client.upload_file(job->image.path);
    if (!blob) {
      std::fprintf(stderr, "upload: %s\n", blob.error().message.c_str());
      return 1;
    }
    job->image.kind = texwarp::proto::ImageSourceSpec::Kind::kBlob;
    job->image.blob = blob->id;
    job->image.path.clear();
  }
  tc::StopSource never;  // a stop that is never requested: the wait runs to the end
  int last_progress = -1;
  tc::WaitOptions wait;
  wait.on_progress = [&](const texwarp::proto::JobStatus& s) { last_progress = s.progress; };
  wait.stop = never.get_token();
  const auto fetched = client.run(*job, argv[3], wait);
  if (!fetched) {
    std::fprintf(stderr, "run: %s (%s)\n", fetched.error().message.c_str(), tc::to_string(fetched.error().code));
    return 1;
  }
  std::printf("job %s\n", fetched->result.job_id.c_str());
  std::printf("progress %d\n", last_progress);
  for (const auto& f : fetched->result.files) {
    std::printf("file %s %llu %s\n", f.name.c_str(), static_cast<unsigned long long>(f.bytes), f.sha256.c_str());
  }
  const auto report = client.report(fetched->result.job_id);
  std::printf("max_px %.17g\n", report && report->image ? report->image->residuals.max_px : -1.0);
  // An invalid job is refused before anything is sent, with the JSON path of the offending value.
  const auto bad = tc::parse_job(R"({"image": {"path": "t.png"}, "warp": {"alpha": "two", "features": []}})");
  std::printf("bad_job_path %s\n", !bad && bad.error().problem ? bad.error().problem->path.c_str() : "-");
  const tc::Result<int> nothing = tc::ClientError{tc::ErrorCode::kInternal, 0, "none", std::nullopt, std::nullopt};
  std::printf("value_or %d\n", nothing.value_or(7));
  return 0;
}
