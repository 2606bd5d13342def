#include "host_sim/cli/static_command.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "host_sim/cli/cli_support.hpp"
#include "model/beam/rotation.hpp"
#include "model/io/beam_problem.hpp"

namespace scopekin::cli {
namespace {

struct StaticOptions {
    std::string problem;
    std::string out;
};

int run_static(const StaticOptions& options) {
    model::io::BeamProblem p = model::io::read_beam_problem_file(options.problem);
    std::cerr << "solving " << options.problem << ": " << p.beam.element_count() << " elements, "
              << p.beam.dof_count() << " DOF, " << p.settings.load_steps << " load steps ..."
              << std::endl;
    const model::StaticReport report = model::solve_static(p.beam, p.loads, p.supports, p.settings);
    std::cout << report.convergence_table();
    std::cout << (report.converged ? "converged" : "NOT converged: " + report.message) << " after "
              << report.total_iterations << " Newton iterations\n\n";
    std::printf("%6s %12s %12s %12s %14s\n", "node", "x [mm]", "y [mm]", "z [mm]",
                "rotation [deg]");
    nlohmann::json nodes = nlohmann::json::array();
    for (std::size_t node : p.output_nodes) {
        const Eigen::Vector3d x = p.beam.position(node);
        const Eigen::Vector3d theta = model::rotation_log(p.beam.rotation(node));
        std::printf("%6zu %12.4f %12.4f %12.4f %14.4f\n", node, x.x(), x.y(), x.z(),
                    theta.norm() * 180.0 / M_PI);
        nodes.push_back({{"node", node},
                         {"arc_length_mm", p.beam.arc_length_mm(node)},
                         {"position_mm", {x.x(), x.y(), x.z()}},
                         {"rotation_vector_rad", {theta.x(), theta.y(), theta.z()}}});
    }
    if (!options.out.empty()) {
        nlohmann::json steps = nlohmann::json::array();
        for (const auto& s : report.steps)
            steps.push_back({{"load_factor", s.load_factor},
                             {"iterations", s.iterations},
                             {"residual_force_N", s.residual_force_N},
                             {"residual_moment_Nmm", s.residual_moment_Nmm},
                             {"converged", s.converged}});
        const nlohmann::json result{
            {"problem", options.problem}, {"converged", report.converged},
            {"message", report.message},  {"newton_iterations", report.total_iterations},
            {"load_steps", steps},        {"nodes", nodes}};
        try {
            cli::PartFile out{
                std::filesystem::path(options.out)};  // OUT.part, renamed when written
            out.stream() << result.dump(2) << "\n";
            out.finish(true);
        } catch (const OutputError& e) {
            std::cerr << "scopekin static: " << e.what() << "\n";
            return 3;
        }
        std::cerr << "wrote " << options.out << "\n";
    }
    return report.converged ? 0 : 1;
}

}  // namespace

void add_static_command(CLI::App& app) {
    auto options = std::make_shared<StaticOptions>();
    CLI::App* cmd =
        app.add_subcommand("static",
                           "Solve a static large-deflection beam problem file (a free scope with "
                           "loads and supports, no colon; "
                           "schema in model/README.md, 'Beam problem files'). Prints the Newton "
                           "convergence per load step and the node poses; "
                           "exit status 0 if converged, 1 if not, 2 for an invalid file.");
    cmd->add_option("problem", options->problem, "Beam problem JSON file")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out, "Also write the result as JSON to this file");
    cmd->callback([options]() { throw CLI::RuntimeError(run_static(*options)); });
}

}  // namespace scopekin::cli
