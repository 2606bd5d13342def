#include "host_sim/view/view_server.hpp"

#include <pthread.h>

#include <atomic>
#include <csignal>
#include <thread>

#include <httplib.h>

namespace scopekin::view {

void serve_page(const std::string& page, const ServeOptions& options) {
    // SIGINT and SIGTERM are taken by one thread that stops the server (blocked here before the
    // server's threads start, so that they inherit the mask).
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

    httplib::Server server;
    server.Get("/", [&page](const httplib::Request&, httplib::Response& res) {
        res.set_content(page, "text/html; charset=utf-8");
    });
    server.Get("/health", [](const httplib::Request&, httplib::Response& res) {
        res.set_content("ok", "text/plain");
    });
    const char* host = "127.0.0.1";
    int port = options.port;
    if (port == 0) {
        port = server.bind_to_any_port(host);
        if (port < 0) throw ViewServerError("no free port on 127.0.0.1");
    } else if (!server.bind_to_port(host, port)) {
        throw ViewServerError("port " + std::to_string(port) +
                              " on 127.0.0.1 cannot be used (in use by another program?); choose "
                              "another with --port, or --port 0 for any free one");
    }
    std::atomic<bool> stopping{false};
    std::thread stopper([&server, &stopping, stop_signals] {
        int signal = 0;
        sigwait(&stop_signals, &signal);
        stopping = true;
        server.stop();
    });
    if (options.on_listening)
        options.on_listening("http://" + std::string(host) + ":" + std::to_string(port) + "/");
    server.listen_after_bind();
    // The server ended without a signal (its socket failed): wake the stopper to end it.
    if (!stopping) pthread_kill(stopper.native_handle(), SIGTERM);
    stopper.join();
}

}  // namespace scopekin::view
