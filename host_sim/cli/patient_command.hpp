#pragma once
// `scopekin patient --seed N [--out FILE]`: one virtual patient as JSON (model/patient/).
// `scopekin patients --count K [--seed S] --out DIR`: K patients (seeds S .. S + K - 1) as
// patients.json, patients.csv, centerlines.csv and a gallery PNG (host_sim/plots/plot_patients.py).
#include <CLI/CLI.hpp>

namespace scopekin::cli {

void add_patient_commands(CLI::App& app);

}  // namespace scopekin::cli
