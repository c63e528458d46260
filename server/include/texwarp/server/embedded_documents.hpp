// The API's documents compiled into texwarpd (embedded at build time by server/cmake/embed_documents.cmake): the JSON
// Schemas of proto/schema/ as they are, and "openapi.json", the OpenAPI 3.1 document bundled with them (every $ref
// internal; server/cmake/bundle_openapi.py).
#pragma once

#include <optional>
#include <string_view>

namespace texwarp::server {

// The document of that file name ("openapi.json", "job.schema.json", ...), or nullopt.
std::optional<std::string_view> embedded_document(std::string_view name);

}  // namespace texwarp::server
