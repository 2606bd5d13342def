#include "host_sim/view/view_server.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include <httplib.h>

#include "hal/linux/spawn_program.hpp"

namespace scopekin::view {
namespace {

sigset_t stop_signals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    return set;
}

/// An idle event stream sends a comment this often (a closed tab is noticed by the failed write).
constexpr std::chrono::seconds kKeepAlive{1};

/// The page is written in pieces of at most this many bytes.
constexpr std::size_t kPageWriteBytes = 64 * 1024;

}  // namespace

PageServer::PageServer(std::string page)
    : server_(std::make_unique<httplib::Server>()),
      page_(std::make_shared<const std::string>(std::move(page))) {
    const sigset_t set = stop_signals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    server_->Get("/", [this](const httplib::Request&, httplib::Response& res) {
        std::shared_ptr<const std::string> served;
        {
            const std::lock_guard lock(mutex_);
            served = page_;
        }
        // Sent as it is, through a sized provider (httplib compresses a body, not a provider):
        // Debian's httplib answers a browser's "Accept-Encoding: br" with brotli at quality 11,
        // 0.83 s of CPU for the 666 kB page, taken from a live run's simulation; on localhost
        // compression buys nothing.
        res.set_content_provider(
            served->size(), "text/html; charset=utf-8",
            [served](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                return sink.write(served->data() + offset, std::min(length, kPageWriteBytes));
            });
    });
    server_->Get("/health", [](const httplib::Request&, httplib::Response& res) {
        res.set_content("ok", "text/plain");
    });
    server_->Get("/events", [this](const httplib::Request&, httplib::Response& res) {
        auto next = std::make_shared<std::size_t>(0);
        res.set_header("Cache-Control", "no-cache");
        res.set_chunked_content_provider(
            "text/event-stream", [this, next](std::size_t, httplib::DataSink& sink) {
                std::unique_lock lock(mutex_);
                const auto end_index = [&] { return first_event_ + events_.size(); };
                changed_.wait_for(lock, kKeepAlive, [&] {
                    return *next < end_index() || events_ended_ || stopping_;
                });
                // A client that joins (or falls) behind the kept history starts at its oldest.
                if (*next < first_event_) *next = first_event_;
                std::string chunk;
                while (*next < end_index())
                    chunk += "data: " + events_[(*next)++ - first_event_] + "\n\n";
                const bool end = events_ended_ || stopping_;
                lock.unlock();
                if (chunk.empty()) chunk = ": keep-alive\n\n";
                if (!sink.write(chunk.data(), chunk.size())) return false;
                if (end) sink.done();
                return true;
            });
    });
}

PageServer::~PageServer() {
    {
        const std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    changed_.notify_all();
    server_->stop();
    if (listener_.joinable()) listener_.join();
    if (signals_.joinable()) {
        bool waiting = false;
        {
            const std::lock_guard lock(mutex_);
            waiting = !signals_done_;
        }
        if (waiting) pthread_kill(signals_.native_handle(), SIGTERM);  // wakes its sigwait
        signals_.join();
    }
}

void PageServer::set_page(std::string page) {
    auto shared = std::make_shared<const std::string>(std::move(page));
    const std::lock_guard lock(mutex_);
    page_ = std::move(shared);
}

void PageServer::publish(std::string message) {
    {
        const std::lock_guard lock(mutex_);
        events_.push_back(std::move(message));
        while (history_limit_ > 0 && events_.size() > history_limit_) {
            events_.pop_front();
            ++first_event_;
        }
    }
    changed_.notify_all();
}

void PageServer::end_events() {
    {
        const std::lock_guard lock(mutex_);
        events_ended_ = true;
    }
    changed_.notify_all();
}

std::size_t PageServer::published() const {
    const std::lock_guard lock(mutex_);
    return first_event_ + events_.size();
}

void PageServer::set_history_limit(std::size_t messages) {
    const std::lock_guard lock(mutex_);
    history_limit_ = messages;
}

std::string PageServer::bind(std::uint16_t port) {
    const char* host = "127.0.0.1";
    int bound = port;
    if (port == 0) {
        bound = server_->bind_to_any_port(host);
        if (bound < 0) throw ViewServerError("no free port on 127.0.0.1");
    } else if (!server_->bind_to_port(host, port)) {
        throw ViewServerError("port " + std::to_string(port) +
                              " on 127.0.0.1 cannot be used (in use by another program?); choose "
                              "another with --port, or --port 0 for any free one");
    }
    return "http://" + std::string(host) + ":" + std::to_string(bound) + "/";
}

void PageServer::start() {
    listener_ = std::thread([this] { server_->listen_after_bind(); });
    signals_ = std::thread([this] {
        const sigset_t set = stop_signals();
        int signal = 0;
        sigwait(&set, &signal);
        std::unique_lock lock(mutex_);
        signals_done_ = true;
        if (stopping_) return;                          // the destructor's wake-up
        if (!graceful_stop_) std::_Exit(128 + signal);  // a live run interrupted, as without us
        signalled_ = true;
        stopping_ = true;
        lock.unlock();
        changed_.notify_all();
        server_->stop();
    });
}

void PageServer::wait_for_stop_signal() {
    std::unique_lock lock(mutex_);
    graceful_stop_ = true;
    changed_.wait(lock, [&] { return signalled_; });
}

/// Asks the desktop to open `url` (xdg-open); says so if it cannot.
void open_in_browser(const std::string& url) {
    std::string program = "xdg-open";
    std::string argument = url;
    char* argv[] = {program.data(), argument.data(), nullptr};
    posix_spawn_file_actions_t quiet;
    posix_spawn_file_actions_init(&quiet);
    posix_spawn_file_actions_addopen(&quiet, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&quiet, 2, "/dev/null", O_WRONLY, 0);
    // The browser must not inherit the server's blocked SIGINT and SIGTERM.
    pid_t pid = 0;
    const int failed = hal::spawn_program(pid, program.c_str(), &quiet, argv);
    posix_spawn_file_actions_destroy(&quiet);
    int status = 0;
    if (failed != 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0)
        std::printf("(no browser could be opened here: open the address above in one)\n");
    std::fflush(stdout);
}

}  // namespace scopekin::view
