#pragma once
// The view's web server on 127.0.0.1 (Debian's cpp-httplib): GET / the page, GET /events the live
// run's messages as server-sent events, GET /health "ok". SIGINT and SIGTERM are taken by one
// thread of the server's: while a live run goes on they end the program at once (exit status 130,
// as without the view), afterwards they end wait_for_stop_signal().
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace scopekin::view {

/// The port cannot be bound (in use, or not allowed): exit status 2.
struct ViewServerError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class PageServer {
public:
    /// Blocks SIGINT and SIGTERM in the calling thread (the server's threads inherit it): create
    /// the server before any other thread.
    explicit PageServer(std::string page);
    ~PageServer();
    PageServer(const PageServer&) = delete;
    PageServer& operator=(const PageServer&) = delete;

    /// What GET / answers from now on.
    void set_page(std::string page);
    /// One message (a JSON text) for /events: kept, and sent to every client from the first.
    void publish(std::string message);
    /// No more messages: each event stream ends once it has sent them all.
    void end_events();
    /// Binds 127.0.0.1:port (0: any free port) and returns the page's address.
    std::string bind(std::uint16_t port);
    /// Serves in a background thread; a signal ends the program (exit 130) until
    /// wait_for_stop_signal() is called.
    void start();
    /// Returns when SIGINT or SIGTERM arrives (then the server has stopped).
    void wait_for_stop_signal();
    /// How many messages have been published.
    std::size_t published() const;
    /// Keep only the last `messages` for clients that connect later (0: all, the default): a
    /// display that runs for hours (`scopekin display --can`) must not grow without bound.
    void set_history_limit(std::size_t messages);

private:
    std::unique_ptr<httplib::Server> server_;
    mutable std::mutex mutex_;
    std::condition_variable changed_;
    std::shared_ptr<const std::string>
        page_;  ///< replaced whole: a request in flight keeps its own
    std::deque<std::string> events_;
    std::size_t first_event_ = 0;    ///< the index of events_.front() among all published
    std::size_t history_limit_ = 0;  ///< 0: keep all
    bool events_ended_ = false;
    bool stopping_ = false;
    bool graceful_stop_ = false;
    bool signalled_ = false;
    bool signals_done_ = false;
    std::thread listener_, signals_;
};

/// Asks the desktop to open `url` (xdg-open); prints that it could not where it cannot.
void open_in_browser(const std::string& url);

}  // namespace scopekin::view
