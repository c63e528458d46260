// The API's documents compiled into texwarpd (proto/schema/*.json, embedded at build time by
// server/cmake/embed_documents.cmake): the OpenAPI 3.1 document and the JSON Schemas it refers to.
#pragma once

#include <optional>
#include <string_view>

namespace texwarp::server {

// The document of that file name ("openapi.json", "job.schema.json", ...), or nullopt.
std::optional<std::string_view> embedded_document(std::string_view name);

}  // namespace texwarp::server
