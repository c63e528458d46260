// Content-addressed blobs (SHA-256 known answers, deduplication, adopted uploads, leftovers cleaned) and where the
// server may read job inputs from (input roots, symlink escapes, unknown blobs), plus small server utilities.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "server_process.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"
#include "texwarp/server/sha256.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(Sha256, KnownAnswers) {
  // FIPS 180-2 examples.
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  Sha256 h;
  h.update("ab");
  h.update("c");
  EXPECT_EQ(h.hex_digest(), sha256_hex("abc"));
}

TEST(BlobStore, StoresByContentOnce) {
  const auto dir = testing::test_folder();
  BlobStore store(dir);
  const auto a = store.put("hello");
  EXPECT_EQ(a.id, "sha256:" + sha256_hex("hello"));
  EXPECT_EQ(a.bytes, 5u);
  EXPECT_TRUE(a.created);
  EXPECT_TRUE(store.contains(a.id));
  EXPECT_EQ(slurp(store.path_of(a.id)), "hello");
  const auto b = store.put("hello");
  EXPECT_EQ(b.id, a.id);
  EXPECT_FALSE(b.created);
  EXPECT_EQ(*store.size(a.id), 5u);
  EXPECT_FALSE(store.contains("sha256:" + sha256_hex("other")));
}

TEST(BlobStore, AdoptsUploadsAndCleansLeftovers) {
  const auto dir = testing::test_folder();
  fs::path leftover;
  {
    BlobStore store(dir);
    const fs::path upload = store.temp_path();
    std::ofstream(upload, std::ios::binary) << "uploaded bytes";
    const auto info = store.adopt(upload);
    EXPECT_TRUE(info.created);
    EXPECT_EQ(info.bytes, 14u);
    EXPECT_FALSE(fs::exists(upload));
    EXPECT_EQ(slurp(store.path_of(info.id)), "uploaded bytes");
    const fs::path again = store.temp_path();
    std::ofstream(again, std::ios::binary) << "uploaded bytes";
    EXPECT_FALSE(store.adopt(again).created);
    EXPECT_FALSE(fs::exists(again));
    leftover = store.temp_path();
    std::ofstream(leftover) << "half an upload";
  }
  BlobStore reopened(dir);  // a restart removes uploads that never finished
  EXPECT_FALSE(fs::exists(leftover));
}

TEST(ServerInputResolver, OnlyUnderInputRootsAndNeverThroughSymlinks) {
  const auto dir = testing::test_folder();
  const fs::path root = dir / "root";
  const fs::path outside = dir / "outside";
  fs::create_directories(root / "sub");
  fs::create_directories(outside);
  std::ofstream(root / "sub" / "t.png") << "x";
  std::ofstream(outside / "secret.png") << "x";
  fs::create_symlink(outside / "secret.png", root / "link.png");
  BlobStore blobs(dir / "data");
  ServerInputResolver resolver(blobs, {fs::canonical(root)});
  proto::ImageSourceSpec image;
  image.kind = proto::ImageSourceSpec::Kind::kPath;
  image.path = (root / "sub" / "t.png").string();
  EXPECT_EQ(resolver.image_file(image, proto::JsonPath{"image"}), fs::canonical(root / "sub" / "t.png").string());

  const auto refusal = [&](const std::string& path) {
    image.path = path;
    try {
      resolver.image_file(image, proto::JsonPath{"image"});
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().str(), "$.image.path");
      return e.detail();
    }
    return std::string("(accepted)");
  };
  EXPECT_THAT(refusal((outside / "secret.png").string()), HasSubstr("not under an input root"));
  EXPECT_THAT(refusal((root / ".." / "outside" / "secret.png").string()), HasSubstr("not under an input root"));
  EXPECT_THAT(refusal((root / "link.png").string()), HasSubstr("outside the input roots"));
  EXPECT_THAT(refusal((root / "missing.png").string()), HasSubstr("no such file"));
  EXPECT_THAT(refusal("sub/t.png"), HasSubstr("absolute"));
  EXPECT_THAT(refusal((root / "sub").string()), HasSubstr("not a regular file"));

  ServerInputResolver no_roots(blobs, {});
  image.path = (root / "sub" / "t.png").string();
  try {
    no_roots.image_file(image, proto::JsonPath{"image"});
    ADD_FAILURE() << "a path was accepted without input roots";
  } catch (const InputError& e) {
    EXPECT_THAT(e.detail(), HasSubstr("POST /v1/blobs"));
  }
  proto::ImageSourceSpec blob;
  blob.kind = proto::ImageSourceSpec::Kind::kBlob;
  blob.blob = "sha256:" + std::string(64, '0');
  try {
    resolver.image_file(blob, proto::JsonPath{"image"});
    ADD_FAILURE() << "an unknown blob was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "$.image.blob");
    EXPECT_THAT(e.detail(), Not(HasSubstr(dir.string())));  // never the server's own layout
  }
}

TEST(ServerConfig, ListenAddresses) {
  EXPECT_EQ(parse_listen_address("127.0.0.1:8080"),
            std::make_pair(std::string("127.0.0.1"), static_cast<unsigned short>(8080)));
  EXPECT_EQ(parse_listen_address("[::1]:0"), std::make_pair(std::string("::1"), static_cast<unsigned short>(0)));
  EXPECT_THROW(parse_listen_address("8080"), std::invalid_argument);
  EXPECT_THROW(parse_listen_address("host:99999"), std::invalid_argument);
  EXPECT_THROW(parse_listen_address("host:80x"), std::invalid_argument);
}

TEST(Timestamps, Rfc3339) {
  EXPECT_EQ(rfc3339_utc(0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(rfc3339_utc(1700000000123), "2023-11-14T22:13:20.123Z");
}

TEST(Metrics, PrometheusTextWithCumulativeBuckets) {
  Metrics m;
  m.observe_request("/v1/jobs", "POST", 202, 0.003);
  m.observe_request("/v1/jobs", "POST", 202, 0.2);
  m.observe_request("/v1/jobs", "POST", 422, 0.001);
  m.job_finished("image", "succeeded", 1.5);
  const std::string text = m.render({{"texwarpd_queue_length", "Jobs waiting.", 3}});
  EXPECT_THAT(text, HasSubstr("texwarpd_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"202\"} 2\n"));
  EXPECT_THAT(text, HasSubstr("texwarpd_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"422\"} 1\n"));
  EXPECT_THAT(text, HasSubstr("texwarpd_http_request_duration_seconds_bucket{route=\"/v1/jobs\",le=\"0.0025\"} 1\n"));
  EXPECT_THAT(text, HasSubstr("texwarpd_http_request_duration_seconds_bucket{route=\"/v1/jobs\",le=\"0.005\"} 2\n"));
  EXPECT_THAT(text, HasSubstr("texwarpd_http_request_duration_seconds_bucket{route=\"/v1/jobs\",le=\"+Inf\"} 3\n"));
  EXPECT_THAT(text, HasSubstr("texwarpd_http_request_duration_seconds_count{route=\"/v1/jobs\"} 3\n"));
  EXPECT_THAT(text, HasSubstr("texwarpd_jobs_finished_total{kind=\"image\",state=\"succeeded\"} 1\n"));
  EXPECT_THAT(text, HasSubstr("# TYPE texwarpd_queue_length gauge\ntexwarpd_queue_length 3\n"));
  EXPECT_DOUBLE_EQ(m.mean_job_seconds(), 1.5);
}

}  // namespace
}  // namespace texwarp::server
