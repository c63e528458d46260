// texwarp_client_example: the shortest useful libtexwarp_client program, as a DCC plugin would use it. Reads a job
// file, uploads its image when the job names a local file, submits, prints progress, and downloads the results.
// Public API only (what an installed package offers). Usage: texwarp_client_example JOB.json OUT_DIR [http://HOST:PORT]
#include <cstdio>
#include <fstream>
#include <sstream>

#include "texwarp/client/client.hpp"
#include "texwarp/client/job_json.hpp"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s JOB.json OUT_DIR [http://HOST:PORT]\n", argv[0]);
    return 2;
  }
  namespace tc = texwarp::client;
  tc::ClientOptions options;
  if (argc > 3) options.server = argv[3];
  tc::Client client(options);

  // The job: any *job*.json of examples/ (checked as the server would).
  std::ifstream in(argv[1]);
  std::stringstream text;
  text << in.rdbuf();
  auto parsed = tc::parse_job(text.str(), argv[1]);
  if (!parsed) {
    std::fprintf(stderr, "%s\n", parsed.error().message.c_str());
    return 2;
  }
  texwarp::proto::JobSpec job = std::move(parsed).value();
  if (job.image.kind == texwarp::proto::ImageSourceSpec::Kind::kPath) {
    const auto blob = client.upload_file(job.image.path);  // content-addressed: uploading twice stores it once
    if (!blob) {
      std::fprintf(stderr, "upload failed: %s\n", blob.error().message.c_str());
      return 1;
    }
    job.image.kind = texwarp::proto::ImageSourceSpec::Kind::kBlob;
    job.image.blob = blob->id;
  }

  tc::WaitOptions wait;
  wait.on_progress = [](const texwarp::proto::JobStatus& s) {
    std::printf("%s %s %d%%\n", s.id.c_str(), texwarp::proto::to_string(s.state), s.progress);
  };
  const auto fetched = client.run(job, argv[2], wait);  // submit, wait, fetch every result file
  if (!fetched) {
    const tc::ClientError& e = fetched.error();
    std::fprintf(stderr, "job failed (%s): %s\n", tc::to_string(e.code), e.message.c_str());
    if (e.problem && !e.problem->path.empty()) std::fprintf(stderr, "  at %s\n", e.problem->path.c_str());
    return 1;
  }
  for (const auto& path : fetched->paths) std::printf("wrote %s\n", path.c_str());
  const auto report = client.report(fetched->result.job_id);  // the report, typed (proto::JobReport)
  if (report && report->image) std::printf("max residual %.3g px\n", report->image->residuals.max_px);
  if (report && report->mesh)
    std::printf("L2 stretch %.4g, max residual %.3g px\n", report->mesh->uvs.l2_stretch, report->mesh->max_residual_px);
  return 0;
}
