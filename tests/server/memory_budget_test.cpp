// texwarpd's memory budget per job and its decoding of untrusted images, against the real server: a 1 kB PNG whose
// header says 16384² RGBA and a valid 65 kB 8192² grey PNG are refused at submission (422, the numbers in the
// detail) while the server's peak memory stays put; truncated PNG and JPEG textures fail their jobs naming the
// truncation, never succeed.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include <png.h>

#include "api_helpers.hpp"
#include "lying_png.hpp"
#include "process_memory.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "test_time.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/base64.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr long kMaxGrowthKiB = 50L * 1024;  // before the budget: 4.3 GB and 2.5 GB
// The refusal reads a header only; before it, the jobs ran ~30 s (both slower alike where everything is).
const double kMaxSeconds = wait_seconds(5.0);

std::string file_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The bytes of `image` written by core's writer as `name` (its extension picks the format).
std::string encoded(const Image& image, const fs::path& dir, const std::string& name) {
  write_image((dir / name).string(), image, PixelFormat::kUint8);
  return file_bytes(dir / name);
}

// A side×side 8-bit grey PNG of zeros (deflate shrinks it about 1000 times), written by libpng from 8-bit rows.
std::string zero_grey_png(int side, const fs::path& dir) {
  const fs::path file = dir / "grey.png";
  std::FILE* out = std::fopen(file.c_str(), "wb");
  EXPECT_NE(out, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  const std::vector<unsigned char> zeros(static_cast<std::size_t>(side), 0);
  if (setjmp(png_jmpbuf(png)) == 0) {  // NOLINT(cert-err52-cpp): libpng's error protocol
    png_init_io(png, out);
    png_set_IHDR(png, info, static_cast<png_uint_32>(side), static_cast<png_uint_32>(side), 8, PNG_COLOR_TYPE_GRAY,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < side; ++y) png_write_row(png, zeros.data());
    png_write_end(png, nullptr);
  } else {
    ADD_FAILURE() << "libpng could not write " << file;
  }
  png_destroy_write_struct(&png, &info);
  std::fclose(out);
  return file_bytes(file);
}

Image noise_image(int w, int h, int channels) {
  Image img(w, h, channels);
  std::uint32_t state = 99;
  for (float& v : img.pixels) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<float>(state >> 24) / 255.0f;
  }
  return img;
}

nlohmann::json job_with_image(const nlohmann::json& image, int output_side) {
  nlohmann::json job = {{"image", image}, {"warp", {{"alpha", 2.0}, {"features", image_job_features()}}}};
  if (output_side > 0) job["output"] = {{"width", output_side}, {"height", output_side}};
  return job;
}

std::string upload(unsigned short port, const std::string& bytes) {
  const HttpReply r = http_request(port, "POST", "/v1/blobs", bytes, {}, "application/octet-stream");
  EXPECT_TRUE(r.status == 201 || r.status == 200) << r.body;
  return r.json().value("id", "");
}

class MemoryBudget : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override {
    server_.reset();
    fs::remove_all(dir_);
  }
  void start(const std::vector<std::string>& args = {}) {
    server_ = std::make_unique<ServerProcess>(dir_ / "data", args);
  }
  unsigned short port() const { return server_->port(); }

  // Submits `job`, expecting a 422 at $.image; checks the time it took and the server's peak memory.
  nlohmann::json expect_refused(const nlohmann::json& job, const std::string& what) {
    const long peak_before = process_memory_kib(server_->pid(), "VmHWM");
    const auto t0 = std::chrono::steady_clock::now();
    const HttpReply r = submit_job(port(), job);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const long grown = process_memory_kib(server_->pid(), "VmHWM") - peak_before;
    std::cout << what << ": " << r.status << " in " << seconds << " s, server peak memory +" << grown << " KiB\n";
    EXPECT_TRUE(is_problem(r, 422, "invalid-job")) << r.body;
    EXPECT_EQ(r.json().value("path", ""), "$.image") << r.body;
    EXPECT_LT(seconds, kMaxSeconds);
    if (kResidentMemoryIsMeasured) {
      EXPECT_LT(grown, kMaxGrowthKiB) << what;
    }
    return r.json();
  }

  fs::path dir_;
  std::unique_ptr<ServerProcess> server_;
};

TEST_F(MemoryBudget, LyingPngHeaderIsRefusedAtSubmissionWithTheNumbers) {
  start({"--max-job-memory-mb", "2048"});
  const std::string bomb = lying_png(16384, 16384);
  ASSERT_LT(bomb.size(), 1200u);
  const nlohmann::json inline_job = job_with_image({{"base64", proto::base64_encode(bomb)}}, 512);
  const std::string detail = expect_refused(inline_job, "inline 1 kB PNG saying 16384² RGBA").value("detail", "");
  EXPECT_THAT(detail, HasSubstr("$.image: this job needs about 5.7 GB ("));
  EXPECT_THAT(detail, HasSubstr("source 16384×16384 RGBA as float 4.3 GB"));
  EXPECT_THAT(detail, HasSubstr("MIP pyramid (at most a third of the source) 1.4 GB"));
  EXPECT_THAT(detail, HasSubstr("the memory limit per job is 2.1 GB (--max-job-memory-mb)"));
  const nlohmann::json blob_job = job_with_image({{"blob", upload(port(), bomb)}}, 512);
  EXPECT_THAT(expect_refused(blob_job, "blob 1 kB PNG saying 16384² RGBA").value("detail", ""),
              HasSubstr("source 16384×16384 RGBA as float 4.3 GB"));
  // Nothing was queued.
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs").json()["jobs"].size(), 0u);
}

TEST_F(MemoryBudget, LyingPngHeaderWithinTheBudgetFailsItsJobHavingUsedWhatTheBytesHeld) {
  start({"--max-job-memory-mb", "8192"});  // 5.7 GB fits: the job is accepted and its decoding must stop early
  const long peak_before = process_memory_kib(server_->pid(), "VmHWM");
  const HttpReply r =
      submit_job(port(), job_with_image({{"base64", proto::base64_encode(lying_png(16384, 16384))}}, 512));
  ASSERT_EQ(r.status, 202) << r.body;
  const auto t0 = std::chrono::steady_clock::now();
  const nlohmann::json status = wait_for_job(port(), r.json()["id"].get<std::string>());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const long grown = process_memory_kib(server_->pid(), "VmHWM") - peak_before;
  std::cout << "accepted 1 kB PNG saying 16384² RGBA: " << status["state"] << " in " << seconds
            << " s, server peak memory +" << grown << " KiB\n";
  ASSERT_EQ(status["state"], "failed") << status.dump();
  EXPECT_EQ(status["error"].value("path", ""), "$.image");
  EXPECT_THAT(status["error"].value("detail", ""), HasSubstr("is truncated or corrupt: "));
  if (kResidentMemoryIsMeasured) {
    EXPECT_LT(grown, 2 * kMaxGrowthKiB);  // the rows its 1000 bytes held, a decoding band, the job's own bookkeeping
  }
}

TEST_F(MemoryBudget, ValidButLargePngIsRefusedUnderASmallBudgetAndSmallJobsStillRun) {
  start({"--max-job-memory-mb", "256"});
  const std::string grey = zero_grey_png(8192, dir_);
  ASSERT_LT(grey.size(), 200u * 1024);
  const std::string detail =
      expect_refused(job_with_image({{"blob", upload(port(), grey)}}, 0), "65 kB 8192² grey PNG").value("detail", "");
  EXPECT_THAT(detail, HasSubstr("source 8192×8192 grey as float 268 MB"));
  EXPECT_THAT(detail, HasSubstr("source positions of 8192×8192 output pixels 1.1 GB"));
  EXPECT_THAT(detail, HasSubstr("the memory limit per job is 268 MB (--max-job-memory-mb)"));
  // The same server runs a job that fits.
  const HttpReply ok = submit_job(port(), image_job());
  ASSERT_EQ(ok.status, 202) << ok.body;
  EXPECT_EQ(wait_for_job(port(), ok.json()["id"].get<std::string>())["state"], "succeeded");
}

TEST_F(MemoryBudget, TruncatedPngAndJpegTexturesFailTheirJobsNamingTheTruncation) {
  start();
  const Image image = noise_image(160, 120, 3);
  for (const std::string name : {"texture.png", "texture.jpg"}) {
    const std::string whole = encoded(image, dir_, name);
    const std::string cut = whole.substr(0, whole.size() / 2);
    for (const nlohmann::json& source :
         {nlohmann::json{{"base64", proto::base64_encode(cut)}}, nlohmann::json{{"blob", upload(port(), cut)}}}) {
      const std::string label = name + " cut in half, " + source.begin().key();
      const HttpReply r = submit_job(port(), job_with_image(source, 64));
      nlohmann::json error;
      if (r.status == 422) {
        error = r.json();
      } else {
        ASSERT_EQ(r.status, 202) << label << ": " << r.body;
        const nlohmann::json status = wait_for_job(port(), r.json()["id"].get<std::string>());
        ASSERT_EQ(status["state"], "failed") << label << ": " << status.dump();
        error = status["error"];
      }
      EXPECT_EQ(error.value("type", ""), "urn:texwarp:problem:invalid-job") << label << ": " << error.dump();
      EXPECT_EQ(error.value("path", ""), "$.image") << label;
      EXPECT_THAT(error.value("detail", ""), HasSubstr("is truncated or corrupt: ")) << label;
      EXPECT_THAT(error.value("detail", ""), Not(HasSubstr(server_->data_dir().string()))) << label;
    }
  }
}

}  // namespace
}  // namespace texwarp::testing
