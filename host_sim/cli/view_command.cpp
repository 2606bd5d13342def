#include "host_sim/cli/view_command.hpp"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/view/view_data.hpp"
#include "host_sim/view/view_page.hpp"
#include "host_sim/view/view_server.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;

struct ViewOptions {
    std::string folder;
    std::uint16_t port = 8765;
    bool no_browser = false;
    std::string export_file;
};

int run_view(const ViewOptions& o) {
    std::string page;
    try {
        std::cerr << "scopekin view: reading " << o.folder << " ..." << std::endl;
        nlohmann::json data;
        if (view::is_evaluation_folder(o.folder)) {
            data = view::read_evaluation_view(
                o.folder, [](std::size_t k, std::size_t n, const std::string& name) {
                    std::cerr << "scopekin view: case " << k + 1 << " of " << n << ": " << name
                              << std::endl;
                });
            for (const auto& [name, why] : data["case_errors"].items())
                std::cerr << "scopekin view: warning: case " << name
                          << " has no replay: " << why.get<std::string>() << "\n";
            std::cerr << "scopekin view: the scorecard of " << data["scorecard"]["cases"].size()
                      << " cases, " << data["case_views"].size() << " with their replay"
                      << std::endl;
        } else if (view::is_discrepancy_folder(o.folder)) {
            data = view::read_discrepancy_view(o.folder);
            std::cerr << "scopekin view: a discrepancy report, verdict "
                      << data["report"]["verdict"].dump() << ", " << data["series"].size()
                      << " output components" << std::endl;
        } else {
            data = view::read_run_view(o.folder);
            std::cerr << "scopekin view: " << data["series"]["time_s"].size()
                      << " timeline points, " << data["alarms"].size() << " alarms, "
                      << data["frames"].size() << " shapes (from "
                      << data["frames_source"].get<std::string>() << ")" << std::endl;
        }
        page = view::render_view_page(data, view::view_assets_folder());
    } catch (const view::ViewDataError& e) {
        std::cerr << "scopekin view: " << e.what() << "\n";
        return 2;
    } catch (const view::ViewAssetsError& e) {
        std::cerr << "scopekin view: " << e.what() << "\n";
        return 2;
    }
    if (!o.export_file.empty()) {
        try {
            PartFile out{fs::path(o.export_file)};
            out.stream() << page;
            out.finish(true);
        } catch (const OutputError& e) {
            std::cerr << "scopekin view: " << e.what() << "\n";
            return 3;
        }
        std::printf(
            "wrote %s (%.1f MB): one file with the data in it; it opens from disk in a "
            "browser, without a server\n",
            o.export_file.c_str(), static_cast<double>(page.size()) / 1e6);
        return 0;
    }
    try {
        view::PageServer server(std::move(page));
        const std::string url = server.bind(o.port);
        server.start();
        std::printf("scopekin view: %s at %s (Ctrl-C to stop)\n", o.folder.c_str(), url.c_str());
        std::fflush(stdout);
        if (!o.no_browser) view::open_in_browser(url);
        server.wait_for_stop_signal();
    } catch (const view::ViewServerError& e) {
        std::cerr << "scopekin view: " << e.what() << "\n";
        return 2;
    }
    return 0;
}

}  // namespace

CLI::Option* add_live_view_options(CLI::App* cmd, bool& view, std::uint16_t& port, bool& no_browser,
                                   const std::string& view_help) {
    CLI::Option* flag = cmd->add_flag("--view", view, view_help);
    cmd->add_option("--port", port, "With --view: the port on 127.0.0.1 (0: any free one)")
        ->default_val(8765)
        ->check(CLI::Range(0, 65535))
        ->needs(flag);
    cmd->add_flag("--no-browser", no_browser,
                  "With --view: do not ask the desktop to open a browser")
        ->needs(flag);
    return flag;
}

void add_view_command(CLI::App& app) {
    auto options = std::make_shared<ViewOptions>();
    CLI::App* cmd = app.add_subcommand(
        "view",
        "Show a run in a browser: the colon (the run's patient, regions coloured, its displaced "
        "shape) and the scope in 3D with the contact forces as arrows, the box's estimate (its "
        "tip with a 1-SD sphere, its stations coloured by force) beside the truth, and a "
        "timeline (handle force and torque, the tip along the colon, the largest contact force, "
        "the alarms as bands, the truth's episodes and the fault flags as strips) with play, "
        "speed, scrub and next alarm. DIR is a folder of `scopekin simulate` (with --frames for "
        "the shapes over time; without, the snapshots' key moments), `scopekin demo` or one case "
        "of `scopekin evaluate`; or a whole evaluation's folder: its scorecard (every estimator "
        "beside the baselines) and its cases, each a link to its replay; or a discrepancy report's "
        "folder (`scopekin discrepancy`): the verdict, the effects, the held-out error per output "
        "and region before and after, and each output measured against the model before and "
        "after. Serves the page on "
        "127.0.0.1 and prints its address until "
        "Ctrl-C, or writes it as one self-contained file with --export. Exit status 0 done, 2 "
        "no run in DIR, a malformed or truncated file, the port in use, or the page's scripts "
        "not built, 3 the exported file cannot be written.");
    cmd->add_option("folder", options->folder,
                    "A run's, an evaluation's or a discrepancy report's folder")
        ->required();
    cmd->add_option("--port", options->port, "Port on 127.0.0.1 (0: any free one; default 8765)")
        ->default_val(8765)
        ->check(CLI::Range(0, 65535));
    cmd->add_flag("--no-browser", options->no_browser,
                  "Do not ask the desktop to open a browser (print the address only)");
    cmd->add_option("--export", options->export_file,
                    "Write the page, the run's data inside, to this HTML file and exit (no "
                    "server; it opens from disk)");
    cmd->callback([options]() { throw CLI::RuntimeError(run_view(*options)); });
}

}  // namespace scopekin::cli
