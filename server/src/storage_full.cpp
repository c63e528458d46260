// A full data folder: see storage_full.hpp.
#include "texwarp/server/storage_full.hpp"

#include <sys/statvfs.h>

#include <cerrno>
#include <system_error>

namespace texwarp::server {

bool is_storage_full(const std::exception& e) {
  const auto* s = dynamic_cast<const std::system_error*>(&e);
  if (s == nullptr) return false;
  const std::error_code& code = s->code();
  const bool errno_code = code.category() == std::generic_category() || code.category() == std::system_category();
  return code == std::errc::no_space_on_device || (errno_code && code.value() == EDQUOT);
}

bool is_storage_full(const boost::system::error_code& ec) {
  return ec == boost::system::errc::no_space_on_device ||
         (ec.category() == boost::system::system_category() && ec.value() == EDQUOT);
}

std::uint64_t free_bytes_of(const std::filesystem::path& folder) {
  struct statvfs vfs {};
  if (::statvfs(folder.c_str(), &vfs) != 0) return 0;
  return static_cast<std::uint64_t>(vfs.f_bavail) * vfs.f_frsize;
}

ServiceError storage_full_error(const std::string& what) {
  return ServiceError(ErrorKind::kStorageFull, "the server's storage is full, so " + what +
                                                   "; retry after the time given (the operator must free space in "
                                                   "the data folder)");
}

}  // namespace texwarp::server
