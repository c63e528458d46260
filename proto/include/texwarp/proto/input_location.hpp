// InputLocation: where in the input an InputError is: a JSON path in a document, or a command-line flag, or the
// input as a whole; optionally the file (or document name) it is in, kept apart so that a server drops it.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "texwarp/proto/export.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

class TEXWARP_API InputLocation {
 public:
  InputLocation() = default;                                // the input as a whole
  InputLocation(JsonPath path) : path_(std::move(path)) {}  // NOLINT: a place in a JSON document
  // A named setting outside any document: a command-line flag ("--device"), an environment variable
  // ("TEXWARP_RETRY_BUDGET") or a request's query parameter ("?state").
  static InputLocation flag(std::string name);
  // A whole file, or a named document ("request body"): kept apart from the place, so that a server can leave
  // its own files out (InputError::message_without_file).
  static InputLocation file(std::string name);

  // The same place in file `name`; a location that already names a file keeps its own.
  InputLocation in_file(std::string name) const;
  // A place in a sub-document re-expressed in the document that holds it at `base`: its JSON path under `base`,
  // or `base` itself when it has none (a file the sub-document was read from, or the whole sub-document). The
  // file and flag are dropped: the result is a place in the holding document.
  InputLocation rebased(const JsonPath& base) const;
  InputLocation without_file() const;

  const std::optional<JsonPath>& json_path() const { return path_; }
  const std::string& flag_name() const { return flag_; }  // empty when not a flag
  const std::string& file_name() const { return file_; }  // empty when in no named file
  bool empty() const { return !path_ && flag_.empty() && file_.empty(); }

  // "file: $.a.b", "$.a.b", "--flag", "file" or "" (the input as a whole).
  std::string str() const;

  friend TEXWARP_API bool operator==(const InputLocation&, const InputLocation&);

 private:
  std::optional<JsonPath> path_;
  std::string flag_;
  std::string file_;
};

}  // namespace texwarp::proto
