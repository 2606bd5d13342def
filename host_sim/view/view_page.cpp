#include "host_sim/view/view_page.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace scopekin::view {
namespace {

namespace fs = std::filesystem;

std::string read_asset(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in)
        throw ViewAssetsError(file.string() +
                              ": missing: the view's scripts are bundled when scopekin is built "
                              "(host_sim/view/web, npm ci and esbuild; ./scopekin.sh installs "
                              "Node.js and npm), or set SCOPEKIN_VIEW_ASSETS to their folder");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

/// Inline text cannot hold "</" followed by "script" or "style" without ending its element;
/// "<\/" means the same inside JSON strings and the scripts' string literals.
std::string escape_end_tags(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (std::size_t k = 0; k < text.size(); ++k) {
        if (text[k] == '<' && k + 1 < text.size() && text[k + 1] == '/') {
            out += "<\\/";
            ++k;
            continue;
        }
        out += text[k];
    }
    return out;
}

/// Replaces the one `marker` of `page` (each marker is used once, in the template's order).
void fill(std::string& page, const std::string& marker, const std::string& text) {
    const std::size_t at = page.find(marker);
    if (at == std::string::npos)
        throw ViewAssetsError("page.html: no " + marker +
                              " (the template does not match scopekin)");
    page.replace(at, marker.size(), text);
}

std::string html_text(const std::string& text) {
    std::string out;
    for (char c : text) {
        if (c == '<')
            out += "&lt;";
        else if (c == '>')
            out += "&gt;";
        else if (c == '&')
            out += "&amp;";
        else
            out += c;
    }
    return out;
}

}  // namespace

fs::path view_assets_folder() {
    if (const char* env = std::getenv("SCOPEKIN_VIEW_ASSETS"); env != nullptr && *env != '\0')
        return env;
    return SCOPEKIN_VIEW_ASSETS;
}

std::string render_view_page(const nlohmann::json& data, const fs::path& assets) {
    std::string page = read_asset(assets / "page.html");
    const std::string style = read_asset(assets / "view.css");
    const std::string script = read_asset(assets / "view.js");
    // Filled at the markers' places in the template, never searched for in inserted text.
    const std::size_t style_at = page.find("@STYLE@");
    const std::size_t data_at = page.find("@DATA@");
    const std::size_t script_at = page.find("@SCRIPT@");
    if (style_at == std::string::npos || data_at == std::string::npos ||
        script_at == std::string::npos || !(style_at < data_at && data_at < script_at))
        throw ViewAssetsError(
            "page.html: @STYLE@, @DATA@ and @SCRIPT@ are not there in that order");
    std::string out;
    out.reserve(page.size() + style.size() + script.size() + (1U << 20U));
    out += page.substr(0, style_at);
    out += escape_end_tags(style);
    out += page.substr(style_at + 7, data_at - style_at - 7);
    out += escape_end_tags(data.dump());
    out += page.substr(data_at + 6, script_at - data_at - 6);
    out += escape_end_tags(script);
    out += page.substr(script_at + 8);
    fill(out, "@TITLE@", html_text(data.value("title", std::string("run"))));  // before <style>
    return out;
}

}  // namespace scopekin::view
