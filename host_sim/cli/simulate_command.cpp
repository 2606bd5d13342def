#include "host_sim/cli/simulate_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <system_error>

#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

struct SimulateOptions {
  std::string scenario;
  std::string out;
  bool quiet = false;
};

/// An output failure (exit status 3).
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.7g", v);
  return buffer;
}

std::string arc_label(double arc_mm) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", arc_mm);
  return buffer;
}

Json vec(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

/// A CSV written as NAME.part and renamed when the run ends: NAME if complete, the
/// "incomplete" name otherwise.
class PartFile {
 public:
  PartFile(fs::path final_path, fs::path incomplete_path)
      : final_(std::move(final_path)), incomplete_(std::move(incomplete_path)), part_(final_.string() + ".part") {
    out_.open(part_);
    if (!out_) throw OutputError("cannot write " + part_.string());
  }
  std::ofstream& stream() { return out_; }
  /// Closes and renames; returns the name it now has.
  fs::path finish(bool complete) {
    out_.close();
    if (out_.fail()) throw OutputError("error while writing " + part_.string());
    const fs::path& target = complete ? final_ : incomplete_;
    std::error_code ec;
    fs::rename(part_, target, ec);
    if (ec) throw OutputError("cannot rename " + part_.string() + " to " + target.string() + ": " + ec.message());
    return target;
  }

 private:
  fs::path final_, incomplete_, part_;
  std::ofstream out_;
};

/// Progress on stderr: a single updating bar on a terminal, a line every 10 % otherwise.
class ProgressBar {
 public:
  explicit ProgressBar(bool quiet) : quiet_(quiet), tty_(isatty(fileno(stderr)) != 0) {}
  void update(const model::SimulationProgress& p) {
    if (quiet_ || !(p.end_s > 0.0)) return;
    const double fraction = std::clamp(p.time_s / p.end_s + 1e-9, 0.0, 1.0);
    const auto now = std::chrono::steady_clock::now();
    last_ = p;
    if (tty_) {
      pending_ = true;
      if (fraction < 1.0 && now - last_draw_ < std::chrono::milliseconds(100)) return;
      pending_ = false;
      last_draw_ = now;
      std::cerr << "\r" << line(p, fraction) << "   " << std::flush;
      drawn_ = true;
    } else {
      const int decile = static_cast<int>(std::floor(fraction * 10.0 + 1e-9));
      if (decile <= last_decile_) return;
      last_decile_ = decile;
      std::cerr << line(p, fraction) << "\n" << std::flush;
    }
  }
  /// Ends the bar (a terminal gets the last state drawn and a newline).
  void done() {
    if (quiet_ || !tty_) return;
    if (pending_) std::cerr << "\r" << line(last_, std::clamp(last_.time_s / last_.end_s + 1e-9, 0.0, 1.0)) << "   ";
    if (drawn_ || pending_) std::cerr << "\n" << std::flush;
    drawn_ = pending_ = false;
  }

 private:
  static std::string line(const model::SimulationProgress& p, double fraction) {
    const int filled = static_cast<int>(std::floor(fraction * 10.0 + 1e-9));
    std::string bar = "[" + std::string(static_cast<std::size_t>(filled), '#') +
                      std::string(static_cast<std::size_t>(10 - filled), ' ') + "]";
    char buffer[160];
    std::snprintf(buffer, sizeof buffer, "%s %3d%% t=%.1f/%.1f s  contacts %zu  F %.1f N", bar.c_str(),
                  static_cast<int>(std::floor(fraction * 100.0 + 1e-9)), p.time_s, p.end_s, p.contacts,
                  p.handle_force_N);
    return buffer;
  }
  bool quiet_;
  bool tty_;
  bool drawn_ = false;
  bool pending_ = false;  // an update not drawn yet (throttled)
  model::SimulationProgress last_;
  int last_decile_ = 0;
  std::chrono::steady_clock::time_point last_draw_{};
};

void remove_stale_outputs(const fs::path& dir) {
  for (const char* name : {"recording.csv", "recording.incomplete.csv", "recording.csv.part", "contacts.csv",
                           "contacts.incomplete.csv", "contacts.csv.part", "summary.json"}) {
    std::error_code ec;
    fs::remove(dir / name, ec);
    if (ec) throw OutputError("cannot remove the old " + (dir / name).string() + ": " + ec.message());
  }
}

void prepare_directory(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw OutputError("cannot create the output directory " + dir.string() +
                                                      (ec ? ": " + ec.message() : ""));
  remove_stale_outputs(dir);
}

/// The keys every summary.json starts with.
Json summary_header(const model::Scenario& sc, const char* kind, bool complete, const std::string& message) {
  Json summary;
  summary["scenario"] = sc.source;
  summary["kind"] = kind;
  summary["description"] = sc.description;
  summary["status"] = complete ? "complete" : "failed";
  summary["message"] = message;
  return summary;
}

void write_summary(const fs::path& path, const Json& summary) {
  std::ofstream out(path);
  out << summary.dump(2) << "\n";
  out.close();
  if (!out) throw OutputError("cannot write " + path.string());
}

std::string recording_header(const model::Scenario& sc, const std::vector<std::size_t>& nodes) {
  std::string h = "time_s,handle_force_N,handle_torque_Nmm,insertion_depth_mm,roll_deg,tip_x_mm,tip_y_mm,tip_z_mm";
  for (std::size_t node : nodes) {
    const double arc = sc.scope.length_mm * static_cast<double>(sc.scope.elements - node) / static_cast<double>(sc.scope.elements);
    const std::string base = "node_" + arc_label(arc) + "mm_";
    h += "," + base + "x_mm," + base + "y_mm," + base + "z_mm";
  }
  h += ",contact_count,contact_force_total_N,contact_force_max_N";
  for (model::ColonRegion r : model::kColonRegionsInOrder) h += ",max_contact_force_" + std::string(model::region_name(r)) + "_N";
  h += ",sticking_contacts,slipping_contacts,tip_driving_angle_deg,gs_sweeps";
  return h;
}

void write_row(std::ostream& out, const model::SimulationSample& s) {
  out << num(s.time_s) << ',' << num(s.handle_force_N) << ',' << num(s.handle_torque_Nmm) << ','
      << num(s.insertion_depth_mm) << ',' << num(s.roll_deg) << ',' << num(s.tip_mm.x()) << ',' << num(s.tip_mm.y()) << ','
      << num(s.tip_mm.z());
  for (const Eigen::Vector3d& p : s.nodes_mm) out << ',' << num(p.x()) << ',' << num(p.y()) << ',' << num(p.z());
  out << ',' << s.contact_count << ',' << num(s.contact_force_total_N) << ',' << num(s.contact_force_max_N);
  for (double f : s.max_contact_force_by_region_N) out << ',' << num(f);
  out << ',' << s.sticking_contacts << ',' << s.slipping_contacts << ','
      << (s.has_tip_driving_angle ? num(s.tip_driving_angle_deg) : std::string()) << ',' << s.gs_sweeps << '\n';
}

void write_contact_rows(std::ostream& out, double time_s, const model::World& world) {
  for (const model::WorldContact& c : world.contacts()) {
    if (!(c.normal_force_N > 0.0)) continue;
    const char* state = c.state == scopekin::contact::ContactState::sticking   ? "sticking"
                        : c.state == scopekin::contact::ContactState::slipping ? "slipping"
                                                                             : "separated";
    out << num(time_s) << ',' << c.scope_node << ',' << num(c.arc_from_tip_mm) << ',' << model::region_name(c.region)
        << ',' << num(c.scope_point_mm.x()) << ',' << num(c.scope_point_mm.y()) << ',' << num(c.scope_point_mm.z()) << ','
        << num(c.normal_force_N) << ',' << num(c.tangential_force_N) << ',' << num(c.friction_coefficient) << ','
        << num(c.driving_angle_rad * 180.0 / M_PI) << ',' << state << ',' << num(c.gap_mm) << '\n';
  }
}

int run_world(const model::Scenario& sc, const SimulateOptions& options) {
  std::unique_ptr<model::World> world = model::build_world(sc);  // ModelError: exit 2, nothing written
  const fs::path dir(options.out);
  prepare_directory(dir);
  const std::vector<std::size_t> nodes = model::output_nodes(sc);
  PartFile recording(dir / "recording.csv", dir / "recording.incomplete.csv");
  recording.stream() << recording_header(sc, nodes) << "\n";
  std::unique_ptr<PartFile> contacts;
  if (sc.outputs.contacts_file) {
    contacts = std::make_unique<PartFile>(dir / "contacts.csv", dir / "contacts.incomplete.csv");
    contacts->stream() << "time_s,scope_node,arc_from_tip_mm,region,x_mm,y_mm,z_mm,normal_force_N,tangential_force_N,"
                          "friction_coefficient,driving_angle_deg,state,gap_mm\n";
  }
  if (!options.quiet)
    std::cerr << "simulating " << sc.source << ": " << sc.procedure.end_s() << " s in steps of " << world->time_step_s()
              << " s, colon '" << sc.colon->name() << "' (" << std::lround(sc.colon->length_mm()) << " mm), scope "
              << sc.scope.length_mm << " mm in " << sc.scope.elements << " elements" << std::endl;

  ProgressBar bar(options.quiet);
  model::SimulationCallbacks callbacks;
  callbacks.on_sample = [&](const model::SimulationSample& s, const model::World& w) {
    write_row(recording.stream(), s);
    if (contacts) write_contact_rows(contacts->stream(), s.time_s, w);
  };
  callbacks.on_progress = [&](const model::SimulationProgress& p) { bar.update(p); };
  const model::SimulationSummary sum = model::run_simulation(*world, sc, callbacks);
  bar.done();

  const fs::path recording_file = recording.finish(sum.complete);
  fs::path contacts_file;
  if (contacts) contacts_file = contacts->finish(sum.complete);

  Json by_region = Json::object();
  for (model::ColonRegion r : model::kColonRegionsInOrder)
    by_region[std::string(model::region_name(r))] = sum.max_contact_force_by_region_N[static_cast<std::size_t>(r)];
  Json files = Json::object();
  files["recording"] = recording_file.filename().string();
  if (contacts) files["contacts"] = contacts_file.filename().string();
  Json summary = summary_header(sc, "world", sum.complete, sum.message);
  summary["failure_time_s"] = sum.complete ? Json(nullptr) : Json(sum.failure_time_s);
  summary["end_time_s"] = sum.end_time_s;
  summary["simulated_time_s"] = sum.simulated_time_s;
  summary["time_step_s"] = world->time_step_s();
  summary["steps"] = sum.steps;
  summary["samples"] = sum.samples;
  summary["sample_rate_Hz"] = sc.outputs.sample_rate_Hz;
  summary["wall_time_s"] = sum.wall_time_s;
  summary["real_time_factor"] = sum.real_time_factor;
  summary["max_handle_force_N"] = sum.max_handle_force_N;
  summary["max_handle_torque_Nmm"] = sum.max_handle_torque_Nmm;
  summary["max_contact_force_N"] = sum.max_contact_force_N;
  summary["max_contact_force_by_region_N"] = by_region;
  summary["max_simultaneous_contacts"] = sum.max_simultaneous_contacts;
  summary["gs_sweeps_mean"] = sum.gs_sweeps_mean;
  summary["gs_sweeps_max"] = sum.gs_sweeps_max;
  summary["dropped_contacts_total"] = sum.dropped_contacts_total;
  summary["material_tangent_fallbacks"] = sum.material_tangent_fallbacks;
  summary["max_penetration_mm"] = sum.max_penetration_mm;
  summary["friction_work_Nmm"] = sum.friction_work_Nmm;
  summary["final_tip_position_mm"] = vec(sum.final_tip_mm);
  summary["final_insertion_depth_mm"] = sum.final_insertion_depth_mm;
  summary["final_roll_deg"] = sum.final_roll_deg;
  summary["warnings"] = sum.warnings;
  summary["files"] = files;
  write_summary(dir / "summary.json", summary);

  for (const std::string& w : sum.warnings) std::cerr << "scopekin simulate: warning: " << w << "\n";
  if (!sum.complete) {
    std::cerr << "scopekin simulate: failed: " << sum.message << "\n"
              << "wrote " << recording_file.string() << " (up to the failure) and " << (dir / "summary.json").string()
              << "\n";
    return 1;
  }
  std::printf("complete: %.3f s simulated in %zu steps, %.1f s wall time (%.2fx real time); max handle force %.2f N, "
              "max contact force %.2f N\n",
              sum.simulated_time_s, sum.steps, sum.wall_time_s, sum.real_time_factor, sum.max_handle_force_N,
              sum.max_contact_force_N);
  std::printf("wrote %s, %s%s%s\n", recording_file.string().c_str(), (dir / "summary.json").string().c_str(),
              contacts ? ", " : "", contacts ? contacts_file.string().c_str() : "");
  return 0;
}

int run_free_beam(model::Scenario& sc, const SimulateOptions& options) {
  model::io::BeamProblem& p = *sc.beam_problem;
  const fs::path dir(options.out);
  prepare_directory(dir);
  PartFile recording(dir / "recording.csv", dir / "recording.incomplete.csv");
  if (!options.quiet)
    std::cerr << "solving the free beam " << sc.source << " statically: " << p.beam.element_count() << " elements, "
              << p.settings.load_steps << " load steps ..." << std::endl;
  const auto start = std::chrono::steady_clock::now();
  const model::StaticReport report = model::solve_static(p.beam, p.loads, p.supports, p.settings);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  recording.stream() << "node,x_mm,y_mm,z_mm\n";
  for (std::size_t node : p.output_nodes) {
    const Eigen::Vector3d x = p.beam.position(node);
    recording.stream() << node << ',' << num(x.x()) << ',' << num(x.y()) << ',' << num(x.z()) << '\n';
  }
  const fs::path recording_file = recording.finish(report.converged);
  std::size_t accepted = 0;
  for (const auto& s : report.steps) accepted += s.converged ? 1 : 0;
  Json summary = summary_header(sc, "free_beam", report.converged, report.message);
  summary["converged"] = report.converged;
  summary["newton_iterations"] = report.total_iterations;
  summary["load_steps_accepted"] = accepted;
  summary["load_steps_attempted"] = report.steps.size();
  summary["wall_time_s"] = wall;
  summary["output_nodes"] = p.output_nodes;
  summary["files"] = Json{{"recording", recording_file.filename().string()}};
  write_summary(dir / "summary.json", summary);
  if (!report.converged) {
    std::cerr << "scopekin simulate: failed: the static solve did not converge: " << report.message << "\n";
    return 1;
  }
  std::printf("complete: converged after %d Newton iterations in %.3f s\nwrote %s, %s\n", report.total_iterations, wall,
              recording_file.string().c_str(), (dir / "summary.json").string().c_str());
  return 0;
}

int run_simulate(const SimulateOptions& options) {
  model::Scenario sc = model::read_scenario_file(options.scenario);  // ModelError: exit 2
  try {
    return sc.kind == model::ScenarioKind::free_beam ? run_free_beam(sc, options) : run_world(sc, options);
  } catch (const OutputError& e) {
    std::cerr << "scopekin simulate: " << e.what() << "\n";
    return 3;
  }
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Run a scenario file (schema in README 'Scenario files'): the scope in a colon driven by a procedure at the "
      "handle, or a free beam problem solved statically. Writes DIR/recording.csv (one row per output sample; a "
      "free beam: one row per output node) and DIR/summary.json. While running the recording is "
      "DIR/recording.csv.part; a run that fails leaves DIR/recording.incomplete.csv and a summary with status "
      "\"failed\". Exit status 0 complete, 1 the run failed (a step or the contact solver did not converge, or the "
      "state became unphysical), 2 invalid scenario (nothing written), 3 an output cannot be written.");
  cmd->add_option("scenario", options->scenario, "Scenario JSON file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", options->out, "Output directory (created if missing; old outputs in it are replaced)")
      ->required();
  cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
  cmd->callback([options]() { throw CLI::RuntimeError(run_simulate(*options)); });
}

}  // namespace scopekin::cli
