// Where an input error is, re-expressed in the job document: the runner's steps call core/mesh functions that
// name places in their own sub-document (or a file); at_path re-places them under the job's JSON path.
#pragma once

#include <string>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::runner {

// An InputError's place re-expressed in the job document: "$..." inside `base` becomes base + "...", a file
// name (the server's own layout, which callers must not see) becomes `base`, a bare key goes under `base`.
inline std::string rebase(const std::string& where, const std::string& base) {
  if (where.empty() || where.find('/') != std::string::npos) return base;
  if (where.rfind(base, 0) == 0) return where;
  if (where[0] == '$') return base + where.substr(1);
  return base + "." + where;
}

// `text` with every mention of `file` (a path on the machine that runs the job) replaced by "the file".
inline std::string without(std::string text, const std::string& file) {
  if (file.empty()) return text;
  for (auto at = text.find(file); at != std::string::npos; at = text.find(file, at)) {
    text.replace(at, file.size(), "the file");
  }
  return text;
}

// Runs f; an InputError from it is re-placed under `base`, and `file` (when given) is not named in its message.
template <typename F>
auto at_path(const std::string& base, F&& f, const std::string& file = {}) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    throw InputError(rebase(e.where(), base), without(e.detail(), file));
  }
}

}  // namespace texwarp::runner
