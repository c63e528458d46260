// The --store value → a JobStore: see job_store_factory.hpp.
#include "texwarp/server/job_store_factory.hpp"

#include <stdexcept>

#include "texwarp/server/postgres_job_store.hpp"
#include "texwarp/server/sqlite_job_store.hpp"

namespace texwarp::server {

std::unique_ptr<JobStore> open_job_store(const std::string& store, const std::filesystem::path& data_dir,
                                         bool migrate) {
  if (store.empty() || store == "sqlite") return std::make_unique<SqliteJobStore>(data_dir / "jobs.sqlite3");
  if (store.rfind("postgresql://", 0) == 0 || store.rfind("postgres://", 0) == 0) {
    return std::make_unique<PostgresJobStore>(store, migrate);
  }
  const std::string shown =
      store.find("://") != std::string::npos ? store.substr(0, store.find("://") + 3) + "…" : store.substr(0, 40);
  throw std::invalid_argument(R"(--store must be "sqlite" or a postgresql:// (or postgres://) URL, not ")" + shown +
                              "\"");
}

}  // namespace texwarp::server
