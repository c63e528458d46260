// TEXWARP_API marks what the shared libtexwarp_client exports (its API and the proto types that API names);
// the library is compiled with hidden visibility, so nothing else (Boost, nlohmann-json, internals) leaves it.
// Empty unless TEXWARP_EXPORT_API is defined (the shared build); a static build exports nothing into a plugin.
#pragma once

#if defined(TEXWARP_EXPORT_API)
#define TEXWARP_API __attribute__((visibility("default")))
#else
#define TEXWARP_API
#endif
