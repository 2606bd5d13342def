#include "host_sim/view/live_view.hpp"

#include <cstdio>

#include "host_sim/evaluate/estimators.hpp"
#include "host_sim/simulator/world_readout.hpp"
#include "host_sim/view/view_page.hpp"
#include "model/colon/bundled_colons.hpp"
#include "model/scope/cf_q160l.hpp"

namespace scopekin::view {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

Json live_page_data(const Json& colon, std::size_t scope_max_points, const std::string& title,
                    const std::string& subtitle, bool box_only) {
    Json data;
    data["schema"] = "scopekin-view/1";
    data["kind"] = "live";
    data["box_only"] = box_only;
    data["title"] = title;
    data["subtitle"] = subtitle;
    data["colon"] = colon;
    data["scope_max_points"] = scope_max_points;
    data["frames"] = Json::array();
    data["frames_source"] = "live";
    Json series;
    for (const char* name :
         {"time_s", "handle_force_N", "handle_torque_Nmm", "insertion_mm", "true_tip_path_mm",
          "box_tip_path_mm", "box_tip_sd_mm", "true_max_force_N", "box_max_force_N",
          "station_path_mm", "station_normal_N"})
        series[name] = Json::array();
    series["stride_periods"] = 1;
    data["series"] = series;
    data["alarms"] = Json::array();
    data["faults"] = Json::array();
    data["fault_names"] = evaluate::fault_flag_names();
    data["truth_episodes"] = {
        {"loop", Json::array()}, {"warning_10N", Json::array()}, {"critical_14N", Json::array()}};
    return data;
}

Json box_page_data(const std::string& title, const std::string& subtitle) {
    const model::ColonTube colon = model::default_colon(model::cf_q160l::kRadius_mm);
    return live_page_data(Json::parse(host_sim::WorldReader::colon_json(colon).dump()), 0, title,
                          subtitle, true);
}

LiveView::LiveView(const Json& page_data, std::uint16_t port)
    : server_(render_view_page(page_data, view_assets_folder())) {
    url_ = server_.bind(port);
    server_.start();
}

void LiveView::step(const host_sim::LiveViewStep& step) {
    if (step.time_s >= last_row_s_ + kLiveRowPeriod_s - 1e-9) {
        rows_.push_back(step.row());
        last_row_s_ = step.time_s;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now - last_send_ < std::chrono::duration<double>(1.0 / kLiveMessagesPerSecond)) return;
    last_send_ = now;
    send(step.frame());
}

void LiveView::send(const std::string& frame) {
    std::string message = "{\"rows\":" + rows_.dump();
    if (!frame.empty()) message += ",\"frame\":" + frame;
    server_.publish(message + "}");
    rows_ = OrderedJson::array();
}

void LiveView::serve_box_page_until_stopped(const char* program) {
    finish(std::string());
    std::printf("%s: the box's view stays at %s (%zu live messages sent; Ctrl-C to stop)\n",
                program, url_.c_str(), messages());
    std::fflush(stdout);
    wait_for_stop_signal();
}

void LiveView::finish(const std::string& replay_page) {
    if (!rows_.empty()) send(std::string());
    if (!replay_page.empty()) server_.set_page(replay_page);
    server_.publish(OrderedJson{{"done", true}, {"replay", !replay_page.empty()}}.dump());
    server_.end_events();
}

}  // namespace scopekin::view
