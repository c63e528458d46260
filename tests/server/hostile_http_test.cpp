// texwarpd against hostile clients, end to end on loopback: bytes that are not UTF-8 anywhere in a request, auth
// before routing, malformed body framing, multipart blob uploads, connection fairness (per-client cap, idle
// eviction, probes over capacity, out of descriptors), parsing off the I/O threads and uploads to a full disk.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "raw_http.hpp"
#include "server_process.hpp"
#include "small_filesystem.hpp"
#include "test_jobs.hpp"
#include "test_time.hpp"
#include "texwarp/proto/base64.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::testing {
namespace {

using Clock = std::chrono::steady_clock;

std::string hex_byte(int b) {
  char buf[4];
  std::snprintf(buf, sizeof buf, "%%%02X", b);
  return buf;
}

std::string get(const std::string& target, const std::string& extra_headers = {}) {
  return "GET " + target + " HTTP/1.1\r\nHost: t\r\n" + extra_headers + "Connection: close\r\n\r\n";
}

// The problem type's slug of a problem+json reply ("" when the body is not a problem).
std::string problem_type(const HttpReply& r) {
  const auto j = r.json();
  if (!j.is_object() || !j.contains("type") || !j["type"].is_string()) return {};
  const std::string type = j["type"];
  const std::string prefix = "urn:texwarp:problem:";
  return type.rfind(prefix, 0) == 0 ? type.substr(prefix.size()) : type;
}

// The server still answers and its process is still there.
void expect_alive(ServerProcess& server) {
  ASSERT_TRUE(server.running()) << server.log();
  const HttpReply r = raw_exchange(server.port(), get("/livez"));
  EXPECT_EQ(r.status, 200) << server.log();
}

// Every reply body is well-formed UTF-8 and, for the problems, JSON that parses.
void expect_clean(const HttpReply& r, const std::string& what) {
  EXPECT_TRUE(proto::is_valid_utf8(r.body)) << what << ": " << r.body;
  if (r.status >= 400) {
    EXPECT_FALSE(problem_type(r).empty()) << what << ": " << r.body;
  }
}

// A connection from a chosen loopback address (127.0.0.x), for the per-client accounting.
class Peer {
 public:
  Peer(unsigned short port, const char* source) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    ::inet_pton(AF_INET, source, &local.sin_addr);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0) throw std::runtime_error("bind");
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    ::inet_pton(AF_INET, "127.0.0.1", &addr.sin_addr);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) throw std::runtime_error("connect");
  }
  ~Peer() { ::close(fd_); }
  Peer(const Peer&) = delete;
  Peer& operator=(const Peer&) = delete;

  void send(const std::string& bytes) const { (void)::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL); }

  // One reply with a Content-Length body; status 0 when the server closed first or nothing came in time.
  HttpReply read_reply(double timeout_s = 10.0) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    std::string data;
    for (;;) {
      const auto head_end = data.find("\r\n\r\n");
      if (head_end != std::string::npos) {
        HttpReply r;
        r.status = std::stoi(data.substr(9, 3));
        const auto cl = data.find("Content-Length: ");
        const std::size_t length = cl == std::string::npos ? 0 : std::stoull(data.substr(cl + 16));
        if (data.size() >= head_end + 4 + length) {
          r.body = data.substr(head_end + 4, length);
          return r;
        }
      }
      const int left =
          static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
      if (left <= 0) return {};
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, left) <= 0) return {};
      char buf[4096];
      const auto n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) return {};
      data.append(buf, static_cast<std::size_t>(n));
    }
  }

  // True when the server closes this connection (EOF or reset) within `timeout_s`.
  bool closed_by_server(double timeout_s) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout_s * 1000)) <= 0) return false;
    char buf[256];
    return ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT) <= 0;
  }

 private:
  int fd_ = -1;
};

// utime + stime of a process, in seconds.
double cpu_seconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string field;
  std::vector<std::string> f;
  while (fields >> field) f.push_back(field);
  // After "pid (comm) ": field 3 (state) is f[0]; utime is field 14, stime field 15.
  return static_cast<double>(std::stoull(f[11]) + std::stoull(f[12])) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// True when `folder` is empty or becomes so within `timeout_s`.
bool becomes_empty(const std::filesystem::path& folder, double timeout_s = 5) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    if (std::filesystem::is_empty(folder)) return true;
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

bool wait_for_log(ServerProcess& server, const std::string& text, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(wait_seconds(timeout_s));
  while (Clock::now() < deadline) {
    if (server.log().find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

// ---------------------------------------------------------------------------------------------------------------
// 1. Bytes that are not UTF-8 never take the server down, and every answer is valid UTF-8.

TEST(HostileHttp, PercentEncodedAndRawHighBytesInPathAndQueryAreAnsweredInValidUtf8) {
  ServerProcess server(test_folder());
  for (int b = 0x80; b <= 0xFF; ++b) {
    const std::string enc = hex_byte(b);
    const std::string raw(1, static_cast<char>(b));
    struct Case {
      std::string target;
      std::vector<int> statuses;  // acceptable
      std::string type;           // expected problem type when a single status is expected
    };
    const std::vector<Case> cases = {
        {"/v1/jobs/" + enc, {404}, "not-found"},
        {"/x" + enc, {404}, "not-found"},
        {"/v1/blobs/" + enc, {404}, "not-found"},
        {"/v1/schemas/" + enc, {404}, "not-found"},
        {"/v1/jobs?state=" + enc, {400}, "bad-query"},
        {"/v1/jobs?limit=" + enc, {400}, "bad-query"},
        {"/v1/jobs?" + enc + "=1", {400}, "bad-query"},
        {"/v1/jobs/" + raw, {400, 404}, ""},
        {"/x" + raw, {400, 404}, ""},
        {"/v1/jobs?state=" + raw, {400}, ""},
    };
    for (const auto& c : cases) {
      const HttpReply r = raw_exchange(server.port(), get(c.target));
      const std::string what = "byte " + std::to_string(b) + " in " + proto::to_valid_utf8(c.target);
      ASSERT_NE(r.status, 0) << what << "\n" << server.log();
      EXPECT_NE(std::find(c.statuses.begin(), c.statuses.end(), r.status), c.statuses.end())
          << what << ": " << r.status;
      if (!c.type.empty()) {
        EXPECT_EQ(problem_type(r), c.type) << what;
      }
      expect_clean(r, what);
    }
  }
  expect_alive(server);
}

// Valid UTF-8 that an error message cuts: the cut falls between characters, never inside one.
TEST(HostileHttp, MessagesCutUserTextBetweenCharacters) {
  ServerProcess server(test_folder());
  const std::vector<std::string> characters = {"\xC3\xA9", "\xE2\x82\xAC", "\xF0\x9F\x98\x80"};  // é € 😀
  const auto pct = [](const std::string& s) {
    std::string out;
    for (unsigned char c : s) out += hex_byte(c);
    return out;
  };
  int checked = 0;
  for (const auto& ch : characters) {
    const std::string twice = ch + ch;
    for (int shift = 0; shift < 4; ++shift) {
      // Each message's cut length (path 120, blob id 80, schema name 60, content type 60, query key 40,
      // limit value 20), with the multi-byte character straddling it.
      struct Case {
        std::string request;
        int status;
        std::string type;
      };
      const auto around = [&](std::size_t cut, std::size_t already) {
        return std::string(cut - already - static_cast<std::size_t>(shift), 'a');
      };
      const std::vector<Case> cases = {
          {get("/" + around(120, 1) + twice), 404, "not-found"},
          {get("/v1/blobs/" + around(80, 0) + pct(ch) + pct(ch)), 404, "not-found"},
          {get("/v1/schemas/" + around(60, 0) + pct(ch) + pct(ch)), 404, "not-found"},
          {get("/v1/jobs?" + around(40, 0) + pct(ch) + pct(ch) + "=1"), 400, "bad-query"},
          {get("/v1/jobs?limit=" + around(20, 0) + pct(ch) + pct(ch)), 400, "bad-query"},
          {"POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: text/" + around(60, 5) + twice +
               "\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}",
           415, "unsupported-media-type"},
      };
      for (const auto& c : cases) {
        const HttpReply r = raw_exchange(server.port(), c.request);
        const std::string what =
            "shift " + std::to_string(shift) + ": " + proto::to_valid_utf8(c.request.substr(0, 60));
        ASSERT_EQ(r.status, c.status) << what << "\n" << server.log();
        EXPECT_EQ(problem_type(r), c.type) << what;
        expect_clean(r, what);
        const std::string detail = r.json().value("detail", "");
        EXPECT_EQ(detail.find("\xEF\xBF\xBD"), std::string::npos) << what << ": a character was cut: " << detail;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * 4 * 6);
  expect_alive(server);
}

TEST(HostileHttp, JobBodiesWithBytesThatAreNotUtf8AreMalformedJson) {
  ServerProcess server(test_folder());
  for (int b = 0x80; b <= 0xFF; ++b) {
    const std::string body = std::string(R"({"name": "x)") + static_cast<char>(b) + R"("})";
    const HttpReply r = http_request(server.port(), "POST", "/v1/jobs", body);
    ASSERT_EQ(r.status, 400) << "byte " << b << "\n" << server.log();
    EXPECT_EQ(problem_type(r), "malformed-json");
    expect_clean(r, "byte " + std::to_string(b));
  }
  // Truncated multi-byte sequences at the end of a string and of the body.
  for (const std::string cut : {"\xC3", "\xE2\x82", "\xF0\x9F\x98"}) {
    for (const std::string& body : {R"({"name": ")" + cut + R"("})", R"({"name": ")" + cut}) {
      const HttpReply r = http_request(server.port(), "POST", "/v1/jobs", body);
      EXPECT_EQ(r.status, 400);
      EXPECT_EQ(problem_type(r), "malformed-json");
      expect_clean(r, "truncated sequence");
    }
  }
  expect_alive(server);
}

// With a token every route but the probes asks for it first: an unknown route is 401, and so is one whose target
// carries bytes that are not UTF-8 (it used to abort the process through the 404).
TEST(HostileHttp, AuthComesBeforeRoutingAndTheBearerSchemeIsCaseInsensitive) {
  const auto dir = test_folder();
  const auto token_file = dir / "token";
  std::ofstream(token_file) << "s3cret-token\n";
  ServerProcess server(dir / "data", {"--token-file", token_file.string()});
  for (const std::string target : {"/v1/jobs/%FF", "/x%C3", "/nowhere", "/v1/jobs/\xFF", "/v1/jobs?state=%FE"}) {
    const HttpReply r = raw_exchange(server.port(), get(target));
    EXPECT_EQ(r.status, 401) << proto::to_valid_utf8(target);
    EXPECT_EQ(problem_type(r), "unauthorized");
    expect_clean(r, target);
  }
  EXPECT_EQ(raw_exchange(server.port(), get("/livez")).status, 200);
  EXPECT_EQ(raw_exchange(server.port(), get("/readyz")).status, 200);
  for (const std::string auth : {"Bearer s3cret-token", "bearer s3cret-token", "BEARER s3cret-token",
                                 "Bearer    s3cret-token  ", "  bEaReR\ts3cret-token"}) {
    const HttpReply r = raw_exchange(server.port(), get("/v1/jobs", "Authorization: " + auth + "\r\n"));
    EXPECT_EQ(r.status, 200) << "Authorization: " << auth << "\n" << r.body;
  }
  for (const std::string auth : {"Bearer wrong", "Basic s3cret-token", "Bearer", "bearers3cret-token"}) {
    const HttpReply r = raw_exchange(server.port(), get("/v1/jobs", "Authorization: " + auth + "\r\n"));
    EXPECT_EQ(r.status, 401) << "Authorization: " << auth;
    EXPECT_EQ(problem_type(r), "unauthorized");
  }
  // Authenticated, an unknown route is a 404 again, in valid UTF-8.
  const HttpReply r = raw_exchange(server.port(), get("/v1/jobs/%FF", "Authorization: Bearer s3cret-token\r\n"));
  EXPECT_EQ(r.status, 404);
  expect_clean(r, "authenticated %FF");
  expect_alive(server);
}

// ---------------------------------------------------------------------------------------------------------------
// 2. Body framing errors are answered.

TEST(HostileHttp, MalformedChunkedBodiesGetA400) {
  ServerProcess server(test_folder());
  const std::vector<std::pair<std::string, std::string>> cases = {{"/v1/jobs", "application/json"},
                                                                  {"/v1/blobs", "application/octet-stream"}};
  for (const auto& [route, type] : cases) {
    std::string head = "POST ";
    head.append(route).append(" HTTP/1.1\r\nHost: t\r\nContent-Type: ").append(type);
    head.append("\r\nTransfer-Encoding: chunked\r\n\r\n");
    for (const std::string bad : {"zz\r\n", "5\r\nabcdeXX\r\n", "-1\r\n", "ffffffffffffffffffff\r\n"}) {
      const HttpReply r = raw_exchange(server.port(), head + bad);
      EXPECT_EQ(r.status, 400) << route << " " << proto::to_valid_utf8(bad);
      EXPECT_EQ(problem_type(r), "malformed-request") << r.body;
      expect_clean(r, route);
    }
  }
  expect_alive(server);
  EXPECT_TRUE(becomes_empty(server.data_dir() / "tmp"));
}

// ---------------------------------------------------------------------------------------------------------------
// 3. Multipart uploads are refused with the way to send raw bytes.

TEST(HostileHttp, MultipartBlobUploadsAreRefusedWith415) {
  ServerProcess server(test_folder());
  const std::string body =
      "--XyZ\r\nContent-Disposition: form-data; name=\"file\"; filename=\"x.png\"\r\nContent-Type: image/png\r\n\r\n" +
      test_png(16) + "\r\n--XyZ--\r\n";
  for (const std::string type : {"multipart/form-data; boundary=XyZ", "Multipart/Mixed; boundary=XyZ"}) {
    const HttpReply r = http_request(server.port(), "POST", "/v1/blobs", body, {}, type);
    EXPECT_EQ(r.status, 415) << type;
    EXPECT_EQ(problem_type(r), "unsupported-media-type");
    EXPECT_NE(r.json().value("detail", "").find("--data-binary"), std::string::npos) << r.body;
  }
  // Nothing was stored; raw bytes still are.
  EXPECT_FALSE(std::filesystem::exists(server.data_dir() / "blobs") &&
               std::filesystem::recursive_directory_iterator(server.data_dir() / "blobs") !=
                   std::filesystem::recursive_directory_iterator());
  const HttpReply ok = http_request(server.port(), "POST", "/v1/blobs", test_png(16), {}, "application/octet-stream");
  EXPECT_EQ(ok.status, 201) << ok.body;
  expect_alive(server);
}

// ---------------------------------------------------------------------------------------------------------------
// 5. Connections: a per-client cap, idle connections make room, probes are always answered, no hot loop on EMFILE.

TEST(HostileHttp, OneClientCannotTakeEveryConnection) {
  ServerProcess server(test_folder(), {"--max-connections", "8", "--max-connections-per-client", "4"});
  // A client holds its 4 connections silently.
  std::vector<std::unique_ptr<Peer>> held;
  held.reserve(4);
  for (int i = 0; i < 4; ++i) held.push_back(std::make_unique<Peer>(server.port(), "127.0.0.2"));
  // Its fifth is refused and closed...
  Peer fifth(server.port(), "127.0.0.2");
  fifth.send(get("/v1/jobs"));
  const HttpReply refused = fifth.read_reply();
  EXPECT_EQ(refused.status, 503);
  EXPECT_EQ(problem_type(refused), "too-many-connections") << refused.body;
  EXPECT_TRUE(fifth.closed_by_server(5));
  // ...but its probes are answered,
  Peer probe(server.port(), "127.0.0.2");
  probe.send(get("/livez"));
  EXPECT_EQ(probe.read_reply().status, 200);
  // and everyone else is served.
  Peer other(server.port(), "127.0.0.3");
  other.send(get("/v1/jobs"));
  EXPECT_EQ(other.read_reply().status, 200);
  EXPECT_TRUE(server.running());
}

TEST(HostileHttp, AtTheGlobalCapIdleKeepAliveConnectionsMakeRoomOldestFirst) {
  ServerProcess server(test_folder(), {"--max-connections", "8", "--max-connections-per-client", "4"});
  // Two clients fill the server with keep-alive connections, each idle after one request.
  std::vector<std::unique_ptr<Peer>> idle;
  for (const char* source : {"127.0.0.2", "127.0.0.3"}) {
    for (int i = 0; i < 4; ++i) {
      idle.push_back(std::make_unique<Peer>(server.port(), source));
      idle.back()->send("GET /v1/jobs HTTP/1.1\r\nHost: t\r\n\r\n");
      ASSERT_EQ(idle.back()->read_reply().status, 200);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));  // distinct idle times: a defined oldest
    }
  }
  // A newcomer is served: the connection idle the longest was closed for it, the others stay open.
  Peer newcomer(server.port(), "127.0.0.4");
  newcomer.send(get("/v1/jobs"));
  EXPECT_EQ(newcomer.read_reply().status, 200);
  EXPECT_TRUE(idle[0]->closed_by_server(5));
  EXPECT_FALSE(idle[1]->closed_by_server(0.2));
  idle[7]->send("GET /v1/jobs HTTP/1.1\r\nHost: t\r\n\r\n");
  EXPECT_EQ(idle[7]->read_reply().status, 200);
  expect_alive(server);
}

TEST(HostileHttp, OverCapacityWithoutIdleConnectionsProbesAreStillAnswered) {
  ServerProcess server(test_folder(), {"--max-connections", "8", "--max-connections-per-client", "4"});
  std::vector<std::unique_ptr<Peer>> busy;  // connected, never sent a byte: not idle between requests
  for (const char* source : {"127.0.0.2", "127.0.0.3"}) {
    for (int i = 0; i < 4; ++i) busy.push_back(std::make_unique<Peer>(server.port(), source));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  Peer refused(server.port(), "127.0.0.4");
  refused.send(get("/v1/jobs"));
  const HttpReply r = refused.read_reply();
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(problem_type(r), "too-many-connections");
  for (const std::string probe : {"/livez", "/readyz"}) {
    Peer p(server.port(), "127.0.0.5");
    p.send(get(probe));
    EXPECT_EQ(p.read_reply().status, 200) << probe;
  }
  EXPECT_TRUE(server.running());
}

// A flood of silent connections over capacity: at most 64 of them are kept (to answer a probe should they ask);
// the rest get a bare 503 and are closed at once, so the flood cannot run the server out of descriptors.
TEST(HostileHttp, AFloodOverCapacityIsTurnedAwayAtOnceAndProbesStillAnswered) {
  ServerProcess server(test_folder(), {"--max-connections", "8", "--max-connections-per-client", "200"});
  std::vector<std::unique_ptr<Peer>> flood;  // connected, never sent a byte
  flood.reserve(8 + 64);
  for (int i = 0; i < 8 + 64; ++i) flood.push_back(std::make_unique<Peer>(server.port(), "127.0.0.2"));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  std::vector<std::unique_ptr<Peer>> beyond;
  beyond.reserve(20);
  for (int i = 0; i < 20; ++i) beyond.push_back(std::make_unique<Peer>(server.port(), "127.0.0.3"));
  for (auto& p : beyond) {
    const HttpReply r = p->read_reply(1.0);  // not after the 2 s a kept connection has to send its header
    EXPECT_EQ(r.status, 503);                // answered without waiting for a request
  }
  const auto open_descriptors =
      std::distance(std::filesystem::directory_iterator("/proc/" + std::to_string(server.pid()) + "/fd"),
                    std::filesystem::directory_iterator());
  EXPECT_LT(open_descriptors, 8 + 64 + 40);  // the server's own files, the store, the 8 + 64 kept connections
  for (const std::string probe : {"/livez", "/readyz"}) {
    flood.pop_back();  // a kept probe slot frees up once one of the kept connections goes
    // The server frees it when it sees that close: at its next turn, later under the full suite's load (100 ms was
    // once too short there). Asked again every 100 ms for up to 5 s; a probe turned away meanwhile is a bare 503.
    int status = 0;
    for (int attempt = 0; attempt < 50 && status != 200; ++attempt) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      Peer p(server.port(), "127.0.0.4");
      p.send(get(probe));
      status = p.read_reply().status;
    }
    EXPECT_EQ(status, 200) << probe;
  }
  EXPECT_TRUE(server.running());
}

// Out of file descriptors the server neither spins on accept() nor stays deaf once descriptors are free again.
TEST(HostileHttp, OutOfDescriptorsAcceptBacksOffInsteadOfSpinning) {
  rlimit saved{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &saved), 0);
  rlimit low = saved;
  low.rlim_cur = 64;  // the child inherits it; ~20 are used by texwarpd itself
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
  std::unique_ptr<ServerProcess> server;
  try {
    server = std::make_unique<ServerProcess>(
        test_folder(), std::vector<std::string>{"--max-connections", "1000", "--max-connections-per-client", "1000"});
  } catch (...) {
  }
  ::setrlimit(RLIMIT_NOFILE, &saved);
  ASSERT_TRUE(server);
  std::vector<std::unique_ptr<RawConnection>> hogs;
  hogs.reserve(70);
  for (int i = 0; i < 70; ++i) hogs.push_back(std::make_unique<RawConnection>(server->port()));
  EXPECT_TRUE(wait_for_log(*server, "out of file descriptors", 5)) << server->log();
  const double cpu0 = cpu_seconds(server->pid());
  const auto t0 = Clock::now();
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const double share = (cpu_seconds(server->pid()) - cpu0) / std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf("texwarpd CPU while out of descriptors: %.1f %%\n", 100 * share);
  EXPECT_LT(share, 0.20);
  hogs.clear();
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  int status = 0;
  while (status != 200 && Clock::now() < deadline) status = raw_exchange(server->port(), get("/livez"), 3).status;
  EXPECT_EQ(status, 200) << server->log();
  EXPECT_TRUE(wait_for_log(*server, "accepting connections again", 5));
}

// ---------------------------------------------------------------------------------------------------------------
// 6. Big job bodies are parsed off the I/O threads: /livez stays fast while two 32 MiB bodies are handled.

TEST(HostileHttp, LivezStaysFastWhileBigJobBodiesAreHandled) {
  ServerProcess server(test_folder(), {"--io-threads", "2"});
  std::string noise(24 * 1024 * 1024 - 64 * 1024, '\0');
  std::mt19937_64 rng(7);
  for (std::size_t i = 0; i + 8 <= noise.size(); i += 8) {
    const std::uint64_t v = rng();
    std::memcpy(&noise[i], &v, 8);
  }
  nlohmann::json job = image_job();
  job["image"]["base64"] = proto::base64_encode(noise);  // decodes, is stored, then is no image: 422
  const std::string body = job.dump();
  ASSERT_LT(body.size(), 32u << 20);
  std::atomic<int> posted{0};
  std::vector<std::thread> posters;
  posters.reserve(2);
  for (int p = 0; p < 2; ++p) {
    posters.emplace_back([&] {
      const HttpReply r = http_request(server.port(), "POST", "/v1/jobs", body);
      EXPECT_EQ(r.status, 422) << r.body;
      ++posted;
    });
  }
  std::vector<double> latencies;
  while (posted.load() < 2) {
    const auto t0 = Clock::now();
    const HttpReply r = raw_exchange(server.port(), get("/livez"), 10);
    latencies.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    EXPECT_EQ(r.status, 200);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  for (auto& t : posters) t.join();
  std::sort(latencies.begin(), latencies.end());
  ASSERT_FALSE(latencies.empty());
  const double max = latencies.back();
  const double p99 = latencies[std::min(latencies.size() - 1, latencies.size() * 99 / 100)];
  std::printf("/livez while two 32 MiB job bodies are handled: %zu probes, p50 %.1f ms, p99 %.1f ms, max %.1f ms\n",
              latencies.size(), 1e3 * latencies[latencies.size() / 2], 1e3 * p99, 1e3 * max);
  EXPECT_LT(p99, 0.5);  // before the bodies were parsed off the I/O threads: max 5.3 s
  EXPECT_LT(max, 1.5);  // a loaded 2-core machine may stall one probe for a moment, never for seconds
  expect_alive(server);
}

// ---------------------------------------------------------------------------------------------------------------
// 7. A blob upload to a full disk is a 507 and leaves no temporary file.

TEST(HostileHttp, BlobUploadToAFullDiskIs507AndLeavesNoTemporaryFile) {
  SmallFilesystem disk(16u << 20);
  if (!disk.available()) GTEST_SKIP() << disk.why_not();
  ServerProcess server(disk.path() / "data");
  disk.fill();
  const std::string bytes(1 << 20, 'b');
  const HttpReply r = http_request(server.port(), "POST", "/v1/blobs", bytes, {}, "application/octet-stream");
  EXPECT_EQ(r.status, 507) << r.body;
  EXPECT_EQ(problem_type(r), "insufficient-storage");
  EXPECT_FALSE(r.header("Retry-After").empty());
  EXPECT_NE(r.json().value("detail", "").find("storage is full"), std::string::npos) << r.body;
  EXPECT_TRUE(becomes_empty(server.data_dir() / "tmp"));
  expect_alive(server);
  disk.release();
  const HttpReply ok = http_request(server.port(), "POST", "/v1/blobs", bytes, {}, "application/octet-stream");
  EXPECT_EQ(ok.status, 201) << ok.body;
  EXPECT_TRUE(becomes_empty(server.data_dir() / "tmp"));
}

}  // namespace
}  // namespace texwarp::testing
