#pragma once
// The page of `scopekin view`: one self-contained HTML file (the bundled scripts and styles of
// host_sim/view/web and the run's data inline), served on localhost or written with --export.
#include <filesystem>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace scopekin::view {

/// The page's scripts were not built (host_sim/view/web, bundled at build time): exit status 2.
struct ViewAssetsError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Where the bundled page.html, view.js and view.css are: $SCOPEKIN_VIEW_ASSETS if set, else the
/// build's folder (compiled in).
std::filesystem::path view_assets_folder();

/// The page with `data` (read_run_view) embedded. Throws ViewAssetsError.
std::string render_view_page(const nlohmann::json& data, const std::filesystem::path& assets);

}  // namespace scopekin::view
