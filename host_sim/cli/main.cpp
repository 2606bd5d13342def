// scopekin: the host-side command line (reference model, host simulator, batch runs).
// Exit status: 0 success, 1 a check failed / a solve did not converge, 2 bad usage or invalid
// input (the message names the field), 3 any other error (e.g. an output file not writable).
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "host_sim/cli/batch_command.hpp"
#include "host_sim/cli/demo_command.hpp"
#include "host_sim/cli/discrepancy_command.hpp"
#include "host_sim/cli/display_command.hpp"
#include "host_sim/cli/evaluate_command.hpp"
#include "host_sim/cli/patient_command.hpp"
#include "host_sim/cli/replay_command.hpp"
#include "host_sim/cli/run_command.hpp"
#include "host_sim/cli/simulate_command.hpp"
#include "host_sim/cli/static_command.hpp"
#include "host_sim/cli/verify_command.hpp"
#include "host_sim/cli/view_command.hpp"
#include "model/model_error.hpp"

int main(int argc, char** argv) {
    CLI::App app{
        "scopekin - colonoscope kinetics: the reference model, its verification, and the host "
        "simulator that runs the "
        "sensor box's unmodified firmware on simulated or recorded data"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "scopekin 0.1.0");
    scopekin::cli::add_verify_command(app);
    scopekin::cli::add_static_command(app);
    scopekin::cli::add_simulate_command(app);
    scopekin::cli::add_run_command(app);
    scopekin::cli::add_replay_command(app);
    scopekin::cli::add_demo_command(app);
    scopekin::cli::add_batch_commands(app);
    scopekin::cli::add_discrepancy_command(app);
    scopekin::cli::add_patient_commands(app);
    scopekin::cli::add_evaluate_commands(app);
    scopekin::cli::add_view_command(app);
    scopekin::cli::add_display_command(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::RuntimeError& status) {
        return status.get_exit_code();
    } catch (const CLI::ParseError& e) {
        // --help / --version exit 0; every usage error exits 2, like an invalid input file.
        return app.exit(e) == 0 ? 0 : 2;
    } catch (const scopekin::model::ModelError& e) {
        std::cerr << "scopekin: invalid model: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "scopekin: error: " << e.what() << "\n";
        return 3;
    }
    return 0;
}
