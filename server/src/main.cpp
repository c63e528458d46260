// texwarpd: the HTTP/JSON batch service. Opens its job store (SQLite: after locking its data folder; PostgreSQL: the
// folder is shared with the other nodes), starts the workers, the node's heartbeat and the HTTP listener;
// SIGTERM/SIGINT drain it (/readyz "draining", new jobs 503, running ones get --shutdown-grace seconds, then are
// released to the queue) and the listener closes once the workers are done. --migrate only migrates the store.
#include <csignal>
#include <cstdio>
#include <fstream>
#include <future>
#include <iostream>
#include <optional>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "texwarp/build_info.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/server/api_router.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/data_dir_lock.hpp"
#include "texwarp/server/http_server.hpp"
#include "texwarp/server/job_service.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/job_store_factory.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"

namespace {

using namespace texwarp::server;

// The data folder's lock, for SQLite only (before anything in the folder is read or changed): nodes sharing a
// PostgreSQL store share the folder too, and coordinate through the database.
std::optional<DataDirLock> lock_for(const ServerConfig& config) {
  if (!config.sqlite_store()) return std::nullopt;
  return std::optional<DataDirLock>(std::in_place, config.data_dir);
}

int migrate(const ServerConfig& config) {
  const auto lock = lock_for(config);
  const auto store = open_job_store(config.store, config.data_dir, true);
  std::cout << "schema at version " << store->schema_version() << std::endl;
  return 0;
}

int serve(const ServerConfig& config) {
  const auto lock = lock_for(config);
  const auto store_owner = open_job_store(config.store, config.data_dir, false);
  JobStore& store = *store_owner;
  BlobStore blobs(config.data_dir,
                  config.sqlite_store() ? BlobStore::Sharing::kExclusive : BlobStore::Sharing::kShared);
  Metrics metrics;
  JobService service(config, store, blobs, metrics);
  ApiRouter router(config, service, metrics);

  boost::asio::io_context ioc(config.io_threads);
  HttpServer http(ioc, config, router, metrics, service);
  const unsigned short port = http.start();
  service.start(port);
  if (!config.port_file.empty())
    texwarp::write_text_file_atomically(config.port_file.string(), std::to_string(port) + "\n");
  log_event(LogLevel::kInfo, "listening",
            {{"host", config.host},
             {"port", port},
             {"data_dir", std::filesystem::absolute(config.data_dir).string()},
             {"store", redacted_store(config.store)},
             {"node", service.node_id()},
             {"lease_s", config.lease_s},
             {"heartbeat_s", config.heartbeat_s},
             {"workers", config.workers},
             {"io_threads", config.io_threads},
             {"auth", config.token.empty() ? "none" : "bearer"},
             {"pid", static_cast<long>(::getpid())}});

  std::promise<int> stop_signal;
  boost::asio::signal_set signals(ioc, SIGTERM, SIGINT);
  signals.async_wait([&](const boost::system::error_code& ec, int signal) {
    if (!ec) stop_signal.set_value(signal);
  });
  std::vector<std::thread> io_threads;
  io_threads.reserve(static_cast<std::size_t>(config.io_threads));
  for (int i = 0; i < config.io_threads; ++i) io_threads.emplace_back([&ioc] { ioc.run(); });

  const int signal = stop_signal.get_future().get();
  log_event(LogLevel::kInfo, "shutting down",
            {{"signal", signal == SIGTERM ? "SIGTERM" : "SIGINT"}, {"grace_s", config.shutdown_grace_s}});
  // A second signal ends the grace: running jobs stop now and run again at the next start.
  signals.async_wait([&](const boost::system::error_code& ec, int) {
    if (ec) return;
    log_event(LogLevel::kInfo, "second signal: running jobs stop now and run again at the next start");
    service.cut_grace();
  });
  // Still listening while the workers finish: /readyz answers "draining", new jobs 503, status and cancel work.
  service.begin_drain();
  service.shutdown(config.shutdown_grace_s);
  http.stop_accepting();
  // Connections still answering a request get a moment; idle keep-alive connections are simply closed.
  for (int i = 0; i < 50 && http.connections() > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ioc.stop();
  for (auto& t : io_threads) t.join();
  log_event(LogLevel::kInfo, "stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int exit_code = 0;
  const auto config = parse_server_config(argc, argv, &exit_code, texwarp::version_line("texwarpd"));
  if (!config) return exit_code;
  try {
    set_log_level(parse_log_level(config->log_level));
    return config->migrate ? migrate(*config) : serve(*config);
  } catch (const DataDirInUse& e) {
    std::cerr << "texwarpd: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "texwarpd failed", {{"error", e.what()}});
    return 1;
  }
}
