#pragma once
// Serves one page on 127.0.0.1 (cpp-httplib) until SIGINT or SIGTERM.
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

namespace scopekin::view {

/// The port cannot be bound (in use, or not allowed): exit status 2.
struct ViewServerError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct ServeOptions {
    std::uint16_t port = 8765;  ///< 0: any free port
    /// Called once the port is bound, with the page's URL (print it, open a browser).
    std::function<void(const std::string& url)> on_listening;
};

/// GET / answers `page` (text/html), GET /health "ok". Returns when SIGINT or SIGTERM arrives.
/// Throws ViewServerError if the port cannot be bound.
void serve_page(const std::string& page, const ServeOptions& options);

}  // namespace scopekin::view
