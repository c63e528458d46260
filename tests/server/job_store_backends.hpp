// The databases the job store suite runs against: a fresh SQLite file, or a fresh database on the test PostgreSQL
// cluster; open() makes one more store object on it (another node).
#pragma once

#include <memory>
#include <string>

#include "texwarp/server/job_store.hpp"

namespace texwarp::testing {

enum class StoreBackend { kSqlite, kPostgres };

class StoreDatabase {
 public:
  virtual ~StoreDatabase() = default;
  virtual std::unique_ptr<server::JobStore> open() = 0;
};

// A fresh, empty database for the current test (removed with the object).
std::unique_ptr<StoreDatabase> make_store_database(StoreBackend backend);

}  // namespace texwarp::testing
