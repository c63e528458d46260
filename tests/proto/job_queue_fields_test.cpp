// The queue's part of the wire format: a job's priority and labels (limits, every refusal at its JSON path, the
// canonical form), the status's priority, labels and node, a batch of jobs (errors at $.jobs[<i>]…) and its answer,
// and the node list of GET /v1/nodes.
#include <gtest/gtest.h>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_batch_codec.hpp"
#include "texwarp/proto/job_labels.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/node_status_codec.hpp"

namespace texwarp::proto {
namespace {

const std::string kBlob = "sha256:" + std::string(64, 'e');

nlohmann::json job(const std::string& extra = "") {
  return parse_json(R"({"image": {"blob": ")" + kBlob +
                        R"("}, "warp": {"features": [{"source": [1, 2], "target": [3, 4]}]})" + extra + "}",
                    "job.json");
}

// "where: detail" of the refusal of a job with `extra` top-level keys.
std::string refusal(const std::string& extra) {
  try {
    decode_job_spec(job(extra));
  } catch (const InputError& e) {
    return e.message_without_file();
  }
  return "(accepted)";
}

std::string where(const nlohmann::json& doc, bool batch) {
  try {
    if (batch) {
      decode_job_batch(doc);
    } else {
      decode_job_spec(doc);
    }
  } catch (const InputError& e) {
    return e.where().str();
  }
  return "(accepted)";
}

TEST(JobPriority, DefaultsToZeroAndIsBounded) {
  EXPECT_EQ(decode_job_spec(job()).priority, 0);
  EXPECT_EQ(decode_job_spec(job(R"(, "priority": 1000)")).priority, 1000);
  EXPECT_EQ(decode_job_spec(job(R"(, "priority": -1000)")).priority, -1000);
  EXPECT_EQ(refusal(R"(, "priority": 1001)"), "$.priority: expected an integer from -1000 to 1000, got 1001");
  EXPECT_EQ(refusal(R"(, "priority": -1001)"), "$.priority: expected an integer from -1000 to 1000, got -1001");
  EXPECT_EQ(refusal(R"(, "priority": 1.5)"), "$.priority: expected an integer, got a number");
  EXPECT_EQ(refusal(R"(, "priority": "high")"), "$.priority: expected an integer, got a string");
  // 2^64 − 1 would wrap to −1 if read as a signed integer.
  EXPECT_EQ(refusal(R"(, "priority": 18446744073709551615)"),
            "$.priority: the integer 18446744073709551615 is out of range");
}

TEST(JobLabels, DecodeEveryValidKeyAndValue) {
  const JobSpec spec =
      decode_job_spec(job(R"(, "labels": {"shot": "sq010/sh0040", "a.b-c_d/E9": "", "x": "ünïcødé"})"));
  EXPECT_EQ(spec.labels, (JobLabels{{"shot", "sq010/sh0040"}, {"a.b-c_d/E9", ""}, {"x", "ünïcødé"}}));
  nlohmann::json many = nlohmann::json::object();
  for (int i = 0; i < 32; ++i) many["k" + std::to_string(i)] = std::string(256, 'v');
  many[std::string(63, 'k')] = "v";
  many.erase("k0");
  nlohmann::json doc = job();
  doc["labels"] = many;
  EXPECT_EQ(decode_job_spec(doc).labels.size(), 32u);
}

TEST(JobLabels, EveryRefusalNamesThePair) {
  EXPECT_EQ(refusal(R"(, "labels": ["a"])"), "$.labels: expected an object of string values, got an array");
  EXPECT_EQ(refusal(R"(, "labels": {"n": 1})"), "$.labels.n: expected a string, got a number");
  EXPECT_EQ(refusal(R"(, "labels": {"": "v"})"), "$.labels.: a label key cannot be empty");
  EXPECT_EQ(refusal(R"(, "labels": {"a b": "v"})"),
            "$.labels.a b: a label key \"a b\" may hold only A-Z a-z 0-9 _ . - /");
  EXPECT_EQ(refusal(R"(, "labels": {"k=v": "v"})"),
            "$.labels.k=v: a label key \"k=v\" may hold only A-Z a-z 0-9 _ . - /");
  EXPECT_EQ(refusal(R"(, "labels": {")" + std::string(64, 'k') + R"(": "v"})").substr(0, 9), "$.labels.");
  EXPECT_NE(refusal(R"(, "labels": {")" + std::string(64, 'k') + R"(": "v"})").find("at most 63 characters, got 64"),
            std::string::npos);
  EXPECT_EQ(refusal(R"(, "labels": {"k": ")" + std::string(257, 'v') + R"("})"),
            "$.labels.k: a label value is at most 256 bytes, got 257");
  // 129 two-byte characters: 258 bytes.
  std::string wide;
  for (int i = 0; i < 129; ++i) wide += "é";
  EXPECT_EQ(refusal(R"(, "labels": {"k": ")" + wide + R"("})"),
            "$.labels.k: a label value is at most 256 bytes, got 258");
  nlohmann::json doc = job();
  doc["labels"] = nlohmann::json::object();
  for (int i = 0; i < 33; ++i) doc["labels"]["k" + std::to_string(i)] = "v";
  EXPECT_EQ(where(doc, false), "$.labels");
  // A value that is not UTF-8 (only possible from C++, the JSON parser refuses such text).
  doc["labels"] = {{"k", std::string("\xff", 1)}};
  EXPECT_EQ(where(doc, false), "$.labels.k");
  // A NUL (PostgreSQL's jsonb refuses it: it was a 500 there) or any other control character.
  for (const char* text : {R"(v\u0000x)", R"(a\nb)", R"(\u007f)"}) {
    EXPECT_EQ(refusal(R"(, "labels": {"k": ")" + std::string(text) + R"("})"),
              "$.labels.k: a label value cannot hold control characters (U+0000–U+001F, U+007F)")
        << text;
  }
}

// A job's name is one line of text: a NUL in it was cut off by PostgreSQL's libpq ("a\u0000b" stored as "a").
TEST(JobName, ControlCharactersAreRefused) {
  EXPECT_EQ(decode_job_spec(job(R"(, "name": "shot 10 — ünïcødé")")).name, "shot 10 — ünïcødé");
  for (const char* text : {R"(a\u0000b)", R"(a\tb)", R"(a\rb)"}) {
    EXPECT_EQ(refusal(R"(, "name": ")" + std::string(text) + R"(")"),
              "$.name: a job name is one line of text: no control characters (U+0000–U+001F, U+007F)")
        << text;
  }
}

TEST(JobLabels, CheckNamesTheQueryParameter) {
  EXPECT_NO_THROW(check_job_label("shot", "sq010", InputLocation::flag("?label"), InputLocation::flag("?label")));
  try {
    check_job_label("sh ot", "v", InputLocation::flag("?label"), InputLocation::flag("?label"));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "?label");
  }
}

TEST(JobQueueFields, CanonicalFormWritesThemAndRoundTrips) {
  const JobSpec plain = decode_job_spec(job());
  const nlohmann::json encoded = encode_job_spec(plain);
  EXPECT_EQ(encoded["priority"], 0);
  EXPECT_EQ(encoded["labels"], nlohmann::json::object());
  const JobSpec tagged = decode_job_spec(job(R"(, "priority": -7, "labels": {"b": "2", "a": "1"})"));
  const nlohmann::json again = encode_job_spec(tagged);
  EXPECT_EQ(again["priority"], -7);
  EXPECT_EQ(again["labels"].dump(), R"({"a":"1","b":"2"})");  // keys sorted: one text per job
  EXPECT_TRUE(decode_job_spec(again) == tagged);
}

TEST(JobStatusCodec, CarriesPriorityLabelsAndNode) {
  JobStatus s;
  s.id = "job_abcdefghijklmnopqrstuvwxyz";
  s.priority = 12;
  s.labels = {{"shot", "sh0040"}};
  s.node = "farm-3:8080";
  s.created_at = "2026-01-01T00:00:00.000Z";
  const nlohmann::json j = encode_job_status(s);
  EXPECT_EQ(j["priority"], 12);
  EXPECT_EQ(j["labels"]["shot"], "sh0040");
  EXPECT_EQ(j["node"], "farm-3:8080");
  const JobStatus back = decode_job_status(j);
  EXPECT_EQ(back.priority, 12);
  EXPECT_EQ(back.labels, s.labels);
  EXPECT_EQ(back.node, "farm-3:8080");
  // An older server's status (no such keys) decodes with the defaults.
  nlohmann::json old = j;
  old.erase("priority");
  old.erase("labels");
  old.erase("node");
  const JobStatus legacy = decode_job_status(old);
  EXPECT_EQ(legacy.priority, 0);
  EXPECT_TRUE(legacy.labels.empty());
  EXPECT_EQ(legacy.node, "");
}

TEST(JobBatchCodec, DecodesEveryJobInOrder) {
  nlohmann::json doc = {{"jobs", nlohmann::json::array()}};
  for (int i = 0; i < 3; ++i) {
    nlohmann::json j = job();
    j["priority"] = i;
    doc["jobs"].push_back(j);
  }
  const JobBatch batch = decode_job_batch(doc);
  ASSERT_EQ(batch.jobs.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(batch.jobs[static_cast<std::size_t>(i)].priority, i);
  const nlohmann::json encoded = encode_job_batch(batch);
  ASSERT_EQ(encoded["jobs"].size(), 3u);
  EXPECT_EQ(encoded["jobs"][2], encode_job_spec(batch.jobs[2]));
}

TEST(JobBatchCodec, RefusalsNameTheJobAndItsValue) {
  nlohmann::json doc = {{"jobs", {job(), job(), job()}}};
  doc["jobs"][2]["warp"]["features"][0]["source"] = "x";
  EXPECT_EQ(where(doc, true), "$.jobs[2].warp.features[0].source");
  doc["jobs"][2] = job();
  doc["jobs"][1]["labels"] = {{"bad key", "v"}};
  EXPECT_EQ(where(doc, true), "$.jobs[1].labels.bad key");
  doc["jobs"][1] = job();
  doc["jobs"][0] = 7;
  EXPECT_EQ(where(doc, true), "$.jobs[0]");
  EXPECT_EQ(where({{"jobs", nlohmann::json::array()}}, true), "$.jobs");
  EXPECT_EQ(where({{"jobs", job()}}, true), "$.jobs");
  EXPECT_EQ(where(nlohmann::json::object(), true), "$.jobs");
  EXPECT_EQ(where({{"jobs", {job()}}, {"priority", 1}}, true), "$.priority");
  EXPECT_EQ(where(nlohmann::json::array(), true), "$");
  nlohmann::json big = {{"jobs", nlohmann::json::array()}};
  for (std::size_t i = 0; i < kMaxBatchJobs; ++i) big["jobs"].push_back(job());
  EXPECT_EQ(where(big, true), "(accepted)");
  big["jobs"].push_back(job());
  try {
    decode_job_batch(big);
    ADD_FAILURE() << "1001 jobs accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.message_without_file(), "$.jobs: a batch holds at most 1000 jobs, got 1001 (send several batches)");
  }
}

TEST(JobBatchCodec, AnswerRoundTrips) {
  JobBatchStatus answer;
  for (const char* id : {"job_aaaaaaaaaaaaaaaaaaaaaaaaaa", "job_bbbbbbbbbbbbbbbbbbbbbbbbbb"}) {
    JobStatus s;
    s.id = id;
    s.created_at = "2026-01-01T00:00:00.000Z";
    answer.jobs.push_back(s);
  }
  const nlohmann::json j = encode_job_batch_status(answer);
  ASSERT_EQ(j["jobs"].size(), 2u);
  EXPECT_EQ(j["jobs"][1]["id"], "job_bbbbbbbbbbbbbbbbbbbbbbbbbb");
  const JobBatchStatus back = decode_job_batch_status(j);
  ASSERT_EQ(back.jobs.size(), 2u);
  EXPECT_EQ(back.jobs[0].id, "job_aaaaaaaaaaaaaaaaaaaaaaaaaa");
  EXPECT_THROW(decode_job_batch_status({{"jobs", {{{"id", "x"}}}}}), InputError);  // no kind, no state
}

TEST(NodeStatusCodec, RoundTripsAndRefusesNonsense) {
  NodeList list;
  NodeStatus n;
  n.id = "farm-1:8080";
  n.address = "10.0.0.1:8080";
  n.version = "1.2.3";
  n.workers = 4;
  n.pid = 4242;
  n.started_at = "2026-01-01T00:00:00.000Z";
  n.last_seen_at = "2026-01-01T00:01:00.000Z";
  n.alive = true;
  n.running = 3;
  list.nodes.push_back(n);
  const nlohmann::json j = encode_node_list(list);
  EXPECT_EQ(j["nodes"][0]["pid"], 4242);
  EXPECT_EQ(j["nodes"][0]["alive"], true);
  const NodeList back = decode_node_list(j);
  ASSERT_EQ(back.nodes.size(), 1u);
  const NodeStatus& b = back.nodes[0];
  EXPECT_EQ(b.id, n.id);
  EXPECT_EQ(b.address, n.address);
  EXPECT_EQ(b.version, n.version);
  EXPECT_EQ(b.workers, 4);
  EXPECT_EQ(b.pid, 4242);
  EXPECT_EQ(b.started_at, n.started_at);
  EXPECT_EQ(b.last_seen_at, n.last_seen_at);
  EXPECT_TRUE(b.alive);
  EXPECT_EQ(b.running, 3);
  nlohmann::json bad = j;
  bad["nodes"][0]["running"] = -1;
  try {
    decode_node_list(bad);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "$.nodes[0].running");
  }
  EXPECT_THROW(decode_node_list({{"nodes", 1}}), InputError);
}

}  // namespace
}  // namespace texwarp::proto
