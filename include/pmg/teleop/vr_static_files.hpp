#pragma once
/// @file vr_static_files.hpp
/// Mapping of an HTTP request target onto a file below the bridge's web root (the WebXR page,
/// data/vr/web). A path outside the root is impossible by construction:
///  - the target must start with '/', at most 1024 bytes; query ("?...") and fragment are dropped;
///  - percent-decoding must be well formed (%XX, hex), and the decoded path may not contain NUL,
///    backslash or control characters;
///  - no segment may start with '.' (so "..", ".", ".git" and the encoded "%2e%2e" are refused);
///  - the result is resolved with symlinks and must still lie below the (resolved) root, be a
///    regular file of at most kVrMaxStaticFileBytes and have an extension of the MIME table;
///  - "/" and paths ending in '/' mean "index.html" in that folder.
/// Setup/server code: allocates, never throws.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace pmg::teleop {

/// Largest file served [bytes].
inline constexpr std::size_t kVrMaxStaticFileBytes = 4u << 20;

/// Outcome of a lookup; `status` is the HTTP status to answer (200, 400 or 404).
struct VrStaticLookup {
  int status = 404;
  std::filesystem::path file;  ///< the file to serve (status 200)
  std::string mime;            ///< its Content-Type (status 200)
  std::string reason;          ///< why not (status != 200), for the log and counters
};

/// Content-Type for @p extension (".html", ".js", ".css", ".json", ".png", ".svg", ".ico",
/// ".txt", ".webmanifest", ".wasm", ".glb"); empty if the extension is not served.
std::string vrMimeType(std::string_view extension);

/// Decodes %XX escapes; false on a malformed escape (the output is then unspecified).
bool vrPercentDecode(std::string_view in, std::string& out);

/// Resolves @p target (the HTTP request target, e.g. "/index.html?synthetic=1") below @p web_root.
VrStaticLookup vrLookupStatic(const std::filesystem::path& web_root, std::string_view target);

}  // namespace pmg::teleop
