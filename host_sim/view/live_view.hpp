#pragma once
// `scopekin simulate --view`: the run streamed to the view's page while it runs (server-sent
// events, at most 25 messages per wall second), then the page becomes the run's replay
// (host_sim/view/README.md, "Live").
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "host_sim/simulator/live_simulation.hpp"
#include "host_sim/view/view_server.hpp"

namespace scopekin::view {

/// Messages per wall second at most (the page draws at its own rate; issue 23 asks >= 20).
inline constexpr double kLiveMessagesPerSecond = 25.0;
/// The timeline's rows: one per this much simulated time at most (every other 10 ms step).
inline constexpr double kLiveRowPeriod_s = 0.02;

class LiveView {
public:
    /// The live page (live_page_data: the colon at rest, no data yet), bound to 127.0.0.1:port
    /// and served. Throws ViewServerError (the port) or ViewAssetsError (the page not built).
    LiveView(const nlohmann::json& page_data, std::uint16_t port);
    /// The page's address.
    const std::string& url() const { return url_; }
    /// Takes one world step (LiveStreams::view_step): its row, and a frame when one is due.
    void step(const host_sim::LiveViewStep& step);
    /// The run has ended: the rows and frame not yet sent, then "done"; the page becomes `replay`
    /// (empty: stays as it is).
    void finish(const std::string& replay_page);
    /// Serves until Ctrl-C (SIGINT or SIGTERM).
    void wait_for_stop_signal() { server_.wait_for_stop_signal(); }
    /// The box's page at the end of its input: finish() as it is, say so on stdout
    /// ("PROGRAM: the box's view stays at URL ..."), serve until Ctrl-C.
    void serve_box_page_until_stopped(const char* program);
    /// Messages sent so far.
    std::size_t messages() const { return server_.published(); }
    /// A page opened later gets only the last `messages` (0: all; PageServer::set_history_limit).
    void keep_last(std::size_t messages) { server_.set_history_limit(messages); }

private:
    void send(const std::string& frame);

    PageServer server_;
    std::string url_;
    nlohmann::ordered_json rows_ = nlohmann::ordered_json::array();
    double last_row_s_ = -1e9;
    std::chrono::steady_clock::time_point last_send_{};
};

/// The live page's data (schema scopekin-view/1, kind "live"): the colon at rest (WorldReader's
/// colon_json), empty series. box_only: the page of the box (`scopekin run --view`): what the box
/// knows, no truth; its colon is the one its reduced model was made in.
nlohmann::json live_page_data(const nlohmann::json& colon, std::size_t scope_max_points,
                              const std::string& title, const std::string& subtitle, bool box_only);

/// The box's live page (`scopekin run --view`, `scopekin display`): box_only, on the colon the
/// box's reduced model was made in (the bundled default, model/reduction/training.json).
nlohmann::json box_page_data(const std::string& title, const std::string& subtitle);

}  // namespace scopekin::view
