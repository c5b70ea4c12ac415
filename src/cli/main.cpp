// pneumaid: parse the command line, run one workflow, map errors to the exit
// statuses of the params spec. No numerics here.
#include <glog/logging.h>

#include <iostream>
#include <map>

#include "commands.h"
#include "pneumaid/ident/fit_result.h"
#include "pneumaid/io/input_error.h"

int main(int argc, char** argv) {
  using namespace pneumaid::cli;
  // Ceres 2.1 logs an ERROR through glog, whatever its logging_type, when a
  // Jacobian evaluation fails after an accepted step; the fit reports that
  // failure itself (its status and message), so the program keeps glog to
  // fatal messages. The library leaves the embedding program's glog alone.
  FLAGS_minloglevel = google::GLOG_FATAL;
  CLI::App app{"pneumaid: identify pneumatic actuators from rig logs"};
  app.set_version_flag("--version", std::string(PNEUMAID_VERSION));
  app.require_subcommand(1);
  // One row per subcommand: its name, what it does, what adds its options.
  const struct {
    const char* name;
    const char* help;
    CommandRunner (*add)(CLI::App*);
  } kCommands[] = {
      {"simulate", "simulate a parameter set for a command", AddSimulateCommand},
      {"check", "validate unit directories without fitting", AddCheckCommand},
      {"identify", "fit a parameter set to a unit's logs", AddIdentifyCommand},
      {"refine", "refit chosen parameters through the simulator on several experiments",
       AddRefineCommand},
      {"validate", "simulate a unit's validation runs and compare", AddValidateCommand},
      {"diagnose",
       "find where a parameter set and a unit's logs disagree and which effect explains it",
       AddDiagnoseCommand},
      {"batch", "identify every unit of a fleet directory", AddBatchCommand},
      {"merge", "combine batch results into the fleet summary", AddMergeCommand},
      {"export", "write a parameter set for controller teams", AddExportCommand},
      {"report", "write a unit's report: one self-contained HTML file", AddReportCommand},
      {"synth", "write a synthetic unit directory from a truth set", AddSynthCommand},
  };
  std::map<CLI::App*, CommandRunner> runners;
  for (const auto& command : kCommands) {
    CLI::App* sub = app.add_subcommand(command.name, command.help);
    runners[sub] = command.add(sub);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int status = app.exit(error);
    return status == 0 ? kSuccess : kBadInput;
  }
  try {
    for (const auto& [subcommand, run] : runners) {
      if (subcommand->parsed()) return run();
    }
  } catch (const pneumaid::InputError& error) {
    std::cerr << "error: " << error.what() << "\n";
    return kBadInput;
  } catch (const pneumaid::FitError& error) {
    std::cerr << "error: " << error.what() << " (nothing written)\n";
    return kNumericalFailure;
  } catch (const std::exception& error) {
    std::cerr << "internal error: " << error.what() << "\n";
    return kUnexpected;
  }
  return kUnexpected;
}
