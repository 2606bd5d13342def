#include "host_sim/cli/patient_command.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "host_sim/cli/cli_support.hpp"
#include "model/model_error.hpp"
#include "model/patient/patient.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;

struct PatientOptions {
    std::uint64_t seed = 0;
    std::string out;
};

struct GalleryOptions {
    std::uint64_t seed = 1;
    std::size_t count = 0;
    std::string out;
    bool quiet = false;
};

/// "1523.4 mm, sigmoid 412.0 mm (n_prone), redraws 1" for the command's stderr line.
std::string describe(const model::PatientSpec& p) {
    char text[200];
    std::snprintf(text, sizeof text, "%.1f mm, sigmoid %.1f mm (%s), redraws %zu",
                  p.total_length_mm(),
                  p.region_length_mm[static_cast<std::size_t>(model::ColonRegion::sigmoid)],
                  std::string(model::sigmoid_shape_name(p.sigmoid_shape)).c_str(), p.redraws);
    return text;
}

int run_patient(const PatientOptions& o) {
    std::vector<std::string> refusals;
    const model::PatientSpec p = model::draw_patient(o.seed, refusals);
    const std::string text = model::patient_to_json(p).dump(2) + "\n";
    std::cerr << "patient seed " << o.seed << ": " << describe(p) << "\n";
    for (std::size_t k = 0; k < refusals.size(); ++k)
        std::cerr << "  draw " << k << " refused: " << refusals[k] << "\n";
    if (o.out.empty()) {
        std::cout << text;
        return 0;
    }
    try {
        PartFile out{fs::path(o.out)};
        out.stream() << text;
        out.finish(true);
    } catch (const OutputError& e) {
        std::cerr << "scopekin patient: " << e.what() << "\n";
        return 3;
    }
    std::cerr << "wrote " << o.out << "\n";
    return 0;
}

/// A CSV cell: quoted (and its quotes doubled) when it holds a comma, a quote or a line break.
std::string csv_cell(const std::string& text) {
    if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
    std::string quoted = "\"";
    for (char c : text) {
        quoted += c;
        if (c == '"') quoted += '"';
    }
    return quoted + "\"";
}

std::string number(double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.6g", v);
    return text;
}

void write_patients_csv(std::ostream& csv, const std::vector<model::PatientSpec>& patients,
                        const std::vector<std::vector<std::string>>& refusals) {
    csv << "seed,redraws,total_length_mm,straightened_path_mm";
    for (auto r : model::kColonRegionsInOrder)
        csv << ',' << model::region_name(r) << "_length_mm";
    for (auto r : model::kColonRegionsInOrder)
        csv << ',' << model::region_name(r) << "_lumen_radius_mm";
    csv << ",sigmoid_shape,sigmoid_loop_radius_mm,sigmoid_loop_tilt_deg,sigmoid_redundancy,"
           "splenic_flexure_angle_deg,hepatic_flexure_angle_deg,transverse_sag_mm,"
           "transverse_width_mm,friction_coefficient,wall_modulus_factor,"
           "mesentery_factor_sigmoid,mesentery_factor_transverse,mesentery_factor_descending,"
           "mesentery_factor_ascending,descending_attachment,ascending_attachment,ei_factor,"
           "distal_section_length_mm,distal_section_factor,redraw_reasons\n";
    for (std::size_t i = 0; i < patients.size(); ++i) {
        const model::PatientSpec& p = patients[i];
        const model::PatientMeasures m = model::measure_patient(p);
        csv << p.seed << ',' << p.redraws << ',' << number(p.total_length_mm()) << ','
            << number(m.straightened_path_mm);
        for (double v : p.region_length_mm)
            csv << ',' << number(v);
        for (double v : p.lumen_radius_mm)
            csv << ',' << number(v);
        csv << ',' << model::sigmoid_shape_name(p.sigmoid_shape) << ','
            << number(p.sigmoid_loop_radius_mm) << ',' << number(p.sigmoid_loop_tilt_deg) << ','
            << number(m.sigmoid_redundancy) << ',' << number(p.splenic_flexure_angle_deg) << ','
            << number(p.hepatic_flexure_angle_deg) << ',' << number(p.transverse_sag_mm) << ','
            << number(m.transverse_width_mm) << ',' << number(p.friction_coefficient) << ','
            << number(p.wall_modulus_factor);
        for (double f : p.mesentery_factor)
            csv << ',' << number(f);
        csv << ',' << (p.descending_mobile ? "mesentery" : "fixed") << ','
            << (p.ascending_mobile ? "mesentery" : "fixed") << ',' << number(p.ei_factor) << ','
            << number(p.distal_section_length_mm) << ',' << number(p.distal_section_factor);
        std::string reasons;
        for (const std::string& r : refusals[i])
            reasons += (reasons.empty() ? "" : " | ") + r;
        csv << ',' << csv_cell(reasons) << '\n';
    }
}

/// The least insertion at the cecum that pleating of the mobile regions can give, over the
/// patients: against the 133 cm colonoscope and the 70-90 cm of standard teaching.
void print_straightened_summary(std::vector<double> path_mm) {
    std::sort(path_mm.begin(), path_mm.end());
    const std::size_t n = path_mm.size();
    const auto under = [&](double limit_mm) {
        return std::lower_bound(path_mm.begin(), path_mm.end(), limit_mm) - path_mm.begin();
    };
    std::printf(
        "straightened path to the cecum (mobile regions on their chords): median %.0f mm, "
        "90th percentile %.0f mm, largest %.0f mm; %td of %zu under 1330 mm, %td under "
        "1000 mm\n",
        path_mm[n / 2], path_mm[std::min(n - 1, (9 * n) / 10)], path_mm.back(), under(1330.0), n,
        under(1000.0));
}

void write_centerlines_csv(std::ostream& csv, const std::vector<model::PatientSpec>& patients) {
    csv << "seed,point,region,x_mm,y_mm,z_mm,inner_radius_mm\n";
    for (const model::PatientSpec& p : patients) {
        const std::vector<model::ColonPoint> points = model::patient_centerline(p);
        for (std::size_t i = 0; i < points.size(); ++i) {
            const auto& q = points[i];
            csv << p.seed << ',' << i << ',' << model::region_name(q.region) << ','
                << number(q.position_mm.x()) << ',' << number(q.position_mm.y()) << ','
                << number(q.position_mm.z()) << ',' << number(q.inner_radius_mm) << '\n';
        }
    }
}

int run_patients(const GalleryOptions& o) {
    if (o.count - 1 > std::numeric_limits<std::uint64_t>::max() - o.seed) {
        std::cerr << "scopekin patients: --seed " << o.seed << " with --count " << o.count
                  << " passes the largest seed (2^64 - 1)\n";
        return 2;
    }
    const fs::path dir(o.out);
    prepare_directory(dir, {"patients.json", "patients.csv", "centerlines.csv", "gallery.png"});
    std::vector<model::PatientSpec> patients;
    std::vector<std::vector<std::string>> refusals(o.count);
    ProgressBar progress(o.quiet);
    std::size_t redraws = 0, redrawn = 0;
    double sum = 0, sum2 = 0;
    std::vector<double> straightened_mm;
    for (std::size_t i = 0; i < o.count; ++i) {
        patients.push_back(model::draw_patient(o.seed + i, refusals[i]));
        redraws += refusals[i].size();
        redrawn += refusals[i].empty() ? 0U : 1U;
        const double total = patients.back().total_length_mm();
        sum += total;
        sum2 += total * total;
        straightened_mm.push_back(model::measure_patient(patients.back()).straightened_path_mm);
        progress.update(static_cast<double>(i + 1) / static_cast<double>(o.count),
                        "patient " + std::to_string(i + 1) + "/" + std::to_string(o.count));
    }
    progress.done();
    {
        PartFile csv(dir / "patients.csv");
        write_patients_csv(csv.stream(), patients, refusals);
        csv.finish(true);
        PartFile lines(dir / "centerlines.csv");
        write_centerlines_csv(lines.stream(), patients);
        lines.finish(true);
    }
    // The gallery, with an argument vector (no shell): the folder's name reaches it as it is.
    std::vector<std::string> argv{SCOPEKIN_PYTHON, SCOPEKIN_PATIENTS_PLOT_SCRIPT};
    if (o.quiet) argv.emplace_back("--quiet");
    argv.push_back(fs::absolute(dir).string());  // absolute: never taken for an option
    const ProgramResult plot = run_program(argv);
    nlohmann::ordered_json all;
    all["first_seed"] = o.seed;
    all["count"] = o.count;
    all["redraws"] = redraws;
    all["patients_redrawn"] = redrawn;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const auto& p : patients)
        list.push_back(model::patient_to_json(p));
    all["patients"] = list;
    write_json(dir / "patients.json", all);  // last: a folder with patients.json is complete
    const double n = static_cast<double>(o.count);
    const double mean = sum / n;
    std::printf("%zu patients (seeds %" PRIu64 " .. %" PRIu64
                "): total length mean %.1f mm, sd %.1f mm; %zu draws refused and redrawn, in %zu "
                "patients\n",
                o.count, o.seed, o.seed + (o.count - 1), mean,
                std::sqrt(std::max(0.0, sum2 / n - mean * mean)), redraws, redrawn);
    print_straightened_summary(straightened_mm);
    if (!plot.ok()) {
        std::cerr << "scopekin patients: the gallery could not be drawn ("
                  << SCOPEKIN_PATIENTS_PLOT_SCRIPT << " " << plot.describe()
                  << "; is python3-matplotlib installed? ./scopekin.sh installs it)\n";
        return 3;
    }
    std::printf("wrote into %s: patients.json, patients.csv, centerlines.csv, gallery.png\n",
                dir.string().c_str());
    return 0;
}

int guarded(const std::function<int()>& run) {
    try {
        return run();
    } catch (const OutputError& e) {
        std::cerr << "scopekin: " << e.what() << "\n";
        return 3;
    }
}

}  // namespace

void add_patient_commands(CLI::App& app) {
    auto one = std::make_shared<PatientOptions>();
    CLI::App* cmd = app.add_subcommand(
        "patient",
        "Draw one virtual patient from the documented family (model/patient/README.md): colon "
        "geometry (region lengths, sigmoid loop, flexure angles, transverse sag, lumen radii), "
        "mechanics (friction, wall modulus, mesentery stiffness, which regions are fixed) and the "
        "scope's bending stiffness. Writes its JSON to stdout (or --out FILE), which a scenario "
        "takes as \"patient\": {\"file\": ...}; the same seed gives the same patient, as "
        "\"patient\": {\"seed\": N} does. A draw that fails the colon checks is redrawn; stderr "
        "says how often and why. Exit status 0 done, 2 bad usage, 3 the file cannot be written.");
    cmd->add_option("--seed", one->seed, "The patient's seed (0 .. 2^64-1)")
        ->required()
        ->check(whole_number());
    cmd->add_option("--out", one->out, "Write the JSON to this file instead of stdout");
    cmd->callback(
        [one]() { throw CLI::RuntimeError(guarded([one] { return run_patient(*one); })); });

    auto many = std::make_shared<GalleryOptions>();
    CLI::App* gallery = app.add_subcommand(
        "patients",
        "Draw K virtual patients (seeds S .. S+K-1) into DIR: patients.json (each patient's JSON, "
        "written last), patients.csv (one row per patient: the drawn parameters, derived "
        "measures, redraws and why), centerlines.csv (every centerline point) and gallery.png "
        "(the first 100 patients in the frontal view, regions coloured, the seed as each "
        "panel's title; drawn by host_sim/plots/plot_patients.py). Prints the total length and "
        "the straightened path to the cecum (the least insertion pleating of the mobile regions "
        "can give; model/patient/README.md). Progress on stderr. Exit "
        "status 0 done, 2 bad usage, 3 an output (or the gallery) cannot be written.");
    gallery->add_option("--count", many->count, "How many patients (1 .. 10000)")
        ->required()
        ->check(CLI::Range(std::size_t{1}, std::size_t{10000}));
    gallery->add_option("--seed", many->seed, "The first seed (0 .. 2^64-1)")
        ->default_val(1)
        ->check(whole_number());
    gallery->add_option("--out", many->out, "Output directory (created if missing)")->required();
    gallery->add_flag("--quiet", many->quiet, "No progress on stderr");
    gallery->callback(
        [many]() { throw CLI::RuntimeError(guarded([many] { return run_patients(*many); })); });
}

}  // namespace scopekin::cli
