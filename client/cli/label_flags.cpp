// `--label KEY=VALUE` flags: see label_flags.hpp.
#include "label_flags.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::cli {

proto::JobLabels parse_label_flags(const std::vector<std::string>& flags) {
  const auto at = InputLocation::flag("--label");
  if (flags.size() > proto::kMaxJobLabels) {
    throw InputError(at, "at most " + std::to_string(proto::kMaxJobLabels) + " labels, got " +
                             std::to_string(flags.size()));
  }
  proto::JobLabels labels;
  for (const auto& flag : flags) {
    const auto eq = flag.find('=');
    if (eq == std::string::npos) {
      throw InputError(at, "expected KEY=VALUE, got \"" + proto::utf8_prefix(flag, 80) + "\"");
    }
    const std::string key = flag.substr(0, eq);
    const std::string value = flag.substr(eq + 1);
    proto::check_job_label(key, value, at, at);
    if (!labels.emplace(key, value).second) throw InputError(at, "the key \"" + key + "\" is given twice");
  }
  return labels;
}

}  // namespace texwarp::cli
